//! Safe waiting and reading on raw descriptors (stdin, the pty, the pty's inotify), so the
//! session waits for input and for the wall clock in one call. The standard library's
//! `Stdin` buffers, which would hide keys from the next wait; these read only what is asked.

use std::io::{self, Write};
use std::os::fd::RawFd;
use std::time::Duration;

/// The terminal's input.
pub const STDIN: RawFd = 0;
/// The terminal's output.
pub const STDOUT: RawFd = 1;

/// A `pollfd` asking whether `fd` can be read.
fn wants_input(fd: RawFd) -> libc::pollfd {
    libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    }
}

/// Waits until one of `fds` has input (or hung up), or `timeout` passes; a signal ends the
/// wait early (the caller checks its quit flag).
pub fn wait_readable(fds: &[RawFd], timeout: Duration) {
    let mut pfds: Vec<libc::pollfd> = fds.iter().map(|&fd| wants_input(fd)).collect();
    let ts = libc::timespec {
        tv_sec: timeout.as_secs() as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: `pfds` is a valid array of its length, `ts` a valid timespec, no signal mask.
    unsafe {
        libc::ppoll(
            pfds.as_mut_ptr(),
            pfds.len() as libc::nfds_t,
            &ts,
            std::ptr::null(),
        )
    };
}

/// True if `fd` has something to read right now (or hung up, or failed: a read says which).
pub fn readable(fd: RawFd) -> bool {
    let mut pfd = wants_input(fd);
    // SAFETY: one valid pollfd, zero timeout.
    let n = unsafe { libc::poll(&mut pfd, 1, 0) };
    n > 0 && pfd.revents & (libc::POLLIN | libc::POLLHUP | libc::POLLERR) != 0
}

/// One `read` of `fd` into `buf`: the bytes read, 0 at end of file.
pub fn read(fd: RawFd, buf: &mut [u8]) -> io::Result<usize> {
    // SAFETY: reading into a buffer of the given length, which outlives the call.
    let n = unsafe { libc::read(fd, buf.as_mut_ptr().cast::<libc::c_void>(), buf.len()) };
    if n < 0 {
        Err(io::Error::last_os_error())
    } else {
        Ok(n as usize)
    }
}

/// Writes `bytes` to standard output at once (errors ignored: a vanished reader must not
/// stop the chip).
pub fn write_stdout(bytes: &[u8]) {
    let mut out = io::stdout().lock();
    let _ = out.write_all(bytes);
    let _ = out.flush();
}
