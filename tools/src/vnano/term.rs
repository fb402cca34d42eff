//! The user's terminal: raw mode that is always restored (normal exit, panic, signal),
//! the quit signals, and the window size.

use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// The terminal settings to put back: (fd, original termios).
static SAVED: Mutex<Option<(i32, libc::termios)>> = Mutex::new(None);

/// Set by SIGINT/SIGTERM/SIGHUP/SIGQUIT; the main loop polls it.
static QUIT: AtomicBool = AtomicBool::new(false);

/// True if `fd` is a terminal.
pub fn is_tty(fd: i32) -> bool {
    // SAFETY: isatty only inspects the descriptor.
    unsafe { libc::isatty(fd) == 1 }
}

/// True if `fd` is a terminal whose foreground is this process's group: its keys are
/// ours. Started with `&` from an interactive shell, the shell keeps the terminal; reading
/// it or changing its settings would stop the process (SIGTTIN, SIGTTOU).
pub fn owns_terminal(fd: i32) -> bool {
    // SAFETY: tcgetpgrp and getpgrp only inspect the descriptor and the process.
    unsafe { is_tty(fd) && libc::tcgetpgrp(fd) == libc::getpgrp() }
}

/// Never stop on terminal output or settings from the background (SIGTTOU with `stty
/// tostop`, SIGTTIN): a stopped process would not end on SIGTERM until continued.
pub fn ignore_background_stops() {
    for sig in [libc::SIGTTOU, libc::SIGTTIN] {
        // SAFETY: ignoring these job-control signals is always allowed.
        unsafe { libc::signal(sig, libc::SIG_IGN) };
    }
}

/// Raw mode on a terminal for as long as the guard lives.
pub struct RawMode {
    _private: (),
}

impl RawMode {
    /// Puts `fd` in raw mode (no echo, no line editing, no signals from keys, no output
    /// processing: the firmware's CR LF go through as they are).
    pub fn enable(fd: i32) -> io::Result<RawMode> {
        // SAFETY: termios is a plain C struct, filled in by tcgetattr before use.
        let mut orig: libc::termios = unsafe { std::mem::zeroed() };
        // SAFETY: valid descriptor and pointer.
        if unsafe { libc::tcgetattr(fd, &mut orig) } != 0 {
            return Err(io::Error::last_os_error());
        }
        let mut raw = orig;
        // SAFETY: cfmakeraw edits the struct in place.
        unsafe { libc::cfmakeraw(&mut raw) };
        *SAVED.lock().unwrap_or_else(|e| e.into_inner()) = Some((fd, orig));
        install_panic_hook();
        // SAFETY: valid descriptor and pointer.
        if unsafe { libc::tcsetattr(fd, libc::TCSAFLUSH, &raw) } != 0 {
            return Err(io::Error::last_os_error());
        }
        Ok(RawMode { _private: () })
    }
}

impl Drop for RawMode {
    fn drop(&mut self) {
        restore();
    }
}

/// Puts the saved terminal settings back (idempotent).
pub fn restore() {
    let saved = SAVED.lock().unwrap_or_else(|e| e.into_inner()).take();
    if let Some((fd, orig)) = saved {
        // SAFETY: the descriptor and settings were valid when saved.
        unsafe { libc::tcsetattr(fd, libc::TCSAFLUSH, &orig) };
    }
}

fn install_panic_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            restore();
            eprint!("\x1b[0m\x1b[?25h\r\n");
            previous(info);
        }));
    });
}

extern "C" fn on_quit_signal(_sig: libc::c_int) {
    // Only an atomic store: async-signal-safe.
    QUIT.store(true, Ordering::SeqCst);
}

/// Routes SIGINT, SIGTERM, SIGHUP and SIGQUIT to [`quit_requested`], so the main loop
/// ends cleanly and restores the terminal.
pub fn catch_quit_signals() {
    for sig in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP, libc::SIGQUIT] {
        // SAFETY: the handler only stores to an atomic; sigaction struct zeroed then filled.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_quit_signal as extern "C" fn(libc::c_int) as usize;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(sig, &action, std::ptr::null_mut());
        }
    }
    // A vanished reader of stdout must give an error, not kill us with the terminal raw.
    // SAFETY: ignoring SIGPIPE is always allowed.
    unsafe { libc::signal(libc::SIGPIPE, libc::SIG_IGN) };
}

/// True once a quit signal has arrived.
pub fn quit_requested() -> bool {
    QUIT.load(Ordering::SeqCst)
}

/// Rows of the terminal on `fd`, if it is one.
pub fn rows(fd: i32) -> Option<u16> {
    // SAFETY: winsize is plain data filled in by the ioctl.
    let mut ws: libc::winsize = unsafe { std::mem::zeroed() };
    // SAFETY: TIOCGWINSZ writes a winsize.
    if unsafe { libc::ioctl(fd, libc::TIOCGWINSZ, &mut ws) } == 0 && ws.ws_row > 0 {
        Some(ws.ws_row)
    } else {
        None
    }
}
