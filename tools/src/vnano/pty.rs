//! The UART as a pseudo-terminal, so minicom, picocom or C-Kermit can connect to the
//! virtual Nano like to `/dev/ttyUSB0`.
//!
//! We keep our own descriptor on the slave side open: a client may come and go (the master
//! never sees a hang-up), and what the firmware sent before the client connected (the boot
//! screen) waits in the line's buffer for it.
//!
//! A Nano resets when a client opens its port (DTR pulls RESET low through a capacitor).
//! That open cannot be seen on the master while we hold the slave open, so
//! [`Pty::watch_opens`] watches the slave node with inotify (`IN_OPEN`) instead.

use std::collections::VecDeque;
use std::ffi::CStr;
use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::path::{Path, PathBuf};

/// Firmware output held back while the client does not read (oldest dropped beyond this,
/// like bytes sent down a serial line nobody listens to).
const OUT_LIMIT: usize = 64 * 1024;

/// The pseudo-terminal standing in for the Nano's USB serial port.
pub struct Pty {
    master: OwnedFd,
    _slave: OwnedFd,
    path: PathBuf,
    link: Option<PathBuf>,
    out: VecDeque<u8>,
    /// inotify on the slave node, when client opens are watched.
    opens: Option<OwnedFd>,
}

fn check(ret: libc::c_int) -> io::Result<libc::c_int> {
    if ret < 0 {
        Err(io::Error::last_os_error())
    } else {
        Ok(ret)
    }
}

impl Pty {
    /// Opens a new pty, raw, 19200 baud, and (if `link` is given) points a symlink at it.
    pub fn open(link: Option<&Path>) -> io::Result<Pty> {
        // SAFETY: plain libc calls on a descriptor we own; ptsname's static buffer is copied
        // at once (single-threaded here).
        let (master, path) = unsafe {
            let fd = check(libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY))?;
            let master = OwnedFd::from_raw_fd(fd);
            check(libc::grantpt(fd))?;
            check(libc::unlockpt(fd))?;
            let name = libc::ptsname(fd);
            if name.is_null() {
                return Err(io::Error::last_os_error());
            }
            let path = PathBuf::from(CStr::from_ptr(name).to_string_lossy().into_owned());
            let flags = check(libc::fcntl(fd, libc::F_GETFL))?;
            check(libc::fcntl(fd, libc::F_SETFL, flags | libc::O_NONBLOCK))?;
            (master, path)
        };
        let c_path = std::ffi::CString::new(path.as_os_str().as_encoded_bytes())
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
        // SAFETY: open/tcgetattr/tcsetattr on the slave we just created.
        let slave = unsafe {
            let fd = check(libc::open(c_path.as_ptr(), libc::O_RDWR | libc::O_NOCTTY))?;
            let slave = OwnedFd::from_raw_fd(fd);
            let mut tio: libc::termios = std::mem::zeroed();
            check(libc::tcgetattr(fd, &mut tio))?;
            libc::cfmakeraw(&mut tio);
            libc::cfsetispeed(&mut tio, libc::B19200);
            libc::cfsetospeed(&mut tio, libc::B19200);
            check(libc::tcsetattr(fd, libc::TCSANOW, &tio))?;
            slave
        };
        let link = match link {
            Some(l) => {
                make_link(&path, l)?;
                Some(l.to_path_buf())
            }
            None => None,
        };
        Ok(Pty {
            master,
            _slave: slave,
            path,
            link,
            out: VecDeque::new(),
            opens: None,
        })
    }

    /// Watches the slave node for clients opening it (see [`Pty::opened`]). Our own open
    /// came before the watch, so it is not reported.
    pub fn watch_opens(&mut self) -> io::Result<()> {
        let c_path = std::ffi::CString::new(self.path.as_os_str().as_encoded_bytes())
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
        // SAFETY: a new inotify descriptor we own; a watch on a valid C string.
        unsafe {
            let fd = check(libc::inotify_init1(libc::IN_NONBLOCK | libc::IN_CLOEXEC))?;
            let fd = OwnedFd::from_raw_fd(fd);
            check(libc::inotify_add_watch(
                fd.as_raw_fd(),
                c_path.as_ptr(),
                libc::IN_OPEN,
            ))?;
            self.opens = Some(fd);
        }
        Ok(())
    }

    /// The inotify descriptor (to poll), if opens are watched.
    pub fn opens_fd(&self) -> Option<i32> {
        self.opens.as_ref().map(|f| f.as_raw_fd())
    }

    /// True if a client opened the pty since the last call (several opens count as one).
    pub fn opened(&mut self) -> bool {
        let Some(fd) = &self.opens else {
            return false;
        };
        let mut any = false;
        // Aligned for `inotify_event`; only the masks matter, not the (empty) names.
        let mut buf = [0u64; 64];
        loop {
            // SAFETY: reading into a buffer of the given length.
            let n = unsafe {
                libc::read(
                    fd.as_raw_fd(),
                    buf.as_mut_ptr() as *mut libc::c_void,
                    std::mem::size_of_val(&buf),
                )
            };
            if n <= 0 {
                return any;
            }
            let bytes = n as usize;
            let mut at = 0;
            let head = std::mem::size_of::<libc::inotify_event>();
            while at + head <= bytes {
                // SAFETY: the kernel wrote whole events; `at` is at an event's start, and
                // read_unaligned copes with the byte offset.
                let ev: libc::inotify_event = unsafe {
                    std::ptr::read_unaligned((buf.as_ptr() as *const u8).add(at) as *const _)
                };
                any |= ev.mask & libc::IN_OPEN != 0;
                at += head + ev.len as usize;
            }
        }
    }

    /// Drops the output held back for a client: after a reset it is the old chip's.
    pub fn discard_output(&mut self) {
        self.out.clear();
    }

    /// The slave device clients open (`/dev/pts/N`).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The master descriptor (to poll for input).
    pub fn fd(&self) -> i32 {
        self.master.as_raw_fd()
    }

    /// Reads whatever the client sent; returns the number of bytes appended.
    pub fn read_into(&mut self, buf: &mut Vec<u8>) -> usize {
        let mut chunk = [0u8; 4096];
        let mut total = 0;
        loop {
            // SAFETY: reading into a stack buffer of the given length.
            let n = unsafe {
                libc::read(
                    self.master.as_raw_fd(),
                    chunk.as_mut_ptr() as *mut libc::c_void,
                    chunk.len(),
                )
            };
            if n <= 0 {
                // EAGAIN: nothing more; EIO cannot happen while we hold the slave open.
                return total;
            }
            let n = n as usize;
            buf.extend_from_slice(&chunk[..n]);
            total += n;
        }
    }

    /// Queues firmware output for the client and writes as much as the line takes.
    pub fn write(&mut self, bytes: &[u8]) {
        self.out.extend(bytes.iter().copied());
        let excess = self.out.len().saturating_sub(OUT_LIMIT);
        self.out.drain(..excess);
        self.flush();
    }

    /// Writes held-back output as far as the line takes it.
    pub fn flush(&mut self) {
        while !self.out.is_empty() {
            let (front, _) = self.out.as_slices();
            // SAFETY: writing from a valid slice.
            let n = unsafe {
                libc::write(
                    self.master.as_raw_fd(),
                    front.as_ptr() as *const libc::c_void,
                    front.len(),
                )
            };
            if n <= 0 {
                return;
            }
            self.out.drain(..n as usize);
        }
    }
}

impl Drop for Pty {
    fn drop(&mut self) {
        if let Some(link) = &self.link {
            // Remove the link only if it still points at our pty.
            if std::fs::read_link(link)
                .map(|t| t == self.path)
                .unwrap_or(false)
            {
                let _ = std::fs::remove_file(link);
            }
        }
    }
}

/// Points `link` at `target`, replacing an old symlink but never a real file.
fn make_link(target: &Path, link: &Path) -> io::Result<()> {
    match std::fs::symlink_metadata(link) {
        Ok(meta) if meta.file_type().is_symlink() => std::fs::remove_file(link)?,
        Ok(_) => {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!(
                    "{} exists and is not a symlink; not replacing it",
                    link.display()
                ),
            ))
        }
        Err(_) => {}
    }
    std::os::unix::fs::symlink(target, link)
}
