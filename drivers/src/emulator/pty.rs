//! A pseudo-terminal in raw mode: the emulator side reads commands and writes records on
//! the master; a driver opens the slave path as it would a serial port.

use crate::emulator::error::EmulatorError;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::time::Duration;

/// A pseudo-terminal: the emulator owns the master side; the slave path is what a driver opens.
pub struct Pty {
    master: OwnedFd,
    /// Kept open so the master never reads EIO while no driver has the slave open.
    _slave: OwnedFd,
    path: String,
}

impl Pty {
    /// Opens a pty pair in raw mode (no echo, no line editing: a serial line).
    pub fn open() -> Result<Pty, EmulatorError> {
        let mut master: libc::c_int = -1;
        let mut slave: libc::c_int = -1;
        let mut name = [0 as libc::c_char; 128];
        // SAFETY: the out-pointers are valid; termios and winsize may be null.
        let rc = unsafe {
            libc::openpty(
                &mut master,
                &mut slave,
                name.as_mut_ptr(),
                std::ptr::null(),
                std::ptr::null(),
            )
        };
        if rc != 0 {
            return Err(EmulatorError::Pty(std::io::Error::last_os_error()));
        }
        // SAFETY: openpty returned two fresh descriptors that we now own.
        let (master, slave) =
            unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
        // SAFETY: `name` was NUL-terminated by openpty.
        let path = unsafe { std::ffi::CStr::from_ptr(name.as_ptr()) }
            .to_string_lossy()
            .into_owned();
        // SAFETY: valid fd and a zeroed termios that tcgetattr fills.
        unsafe {
            let mut t: libc::termios = std::mem::zeroed();
            if libc::tcgetattr(slave.as_raw_fd(), &mut t) == 0 {
                libc::cfmakeraw(&mut t);
                libc::tcsetattr(slave.as_raw_fd(), libc::TCSANOW, &t);
            }
        }
        Ok(Pty {
            master,
            _slave: slave,
            path,
        })
    }

    /// The slave device path (`/dev/pts/N`).
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Reads what is available within `timeout` (empty when nothing came).
    pub(crate) fn read_timeout(&self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        let mut pfd = libc::pollfd {
            fd: self.master.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd.
        let n = unsafe { libc::poll(&mut pfd, 1, timeout.as_millis() as libc::c_int) };
        if n <= 0 || pfd.revents & libc::POLLIN == 0 {
            return Ok(0);
        }
        // SAFETY: buf is valid for buf.len() bytes.
        let k = unsafe { libc::read(self.master.as_raw_fd(), buf.as_mut_ptr().cast(), buf.len()) };
        if k < 0 {
            Err(std::io::Error::last_os_error())
        } else {
            Ok(k as usize)
        }
    }

    /// Writes all bytes (the pty buffer is large; a full buffer waits briefly).
    pub(crate) fn write_all(&self, mut bytes: &[u8]) -> std::io::Result<()> {
        while !bytes.is_empty() {
            // SAFETY: bytes is valid for its length.
            let k =
                unsafe { libc::write(self.master.as_raw_fd(), bytes.as_ptr().cast(), bytes.len()) };
            if k < 0 {
                let e = std::io::Error::last_os_error();
                if e.kind() == std::io::ErrorKind::WouldBlock
                    || e.kind() == std::io::ErrorKind::Interrupted
                {
                    std::thread::sleep(Duration::from_millis(1));
                    continue;
                }
                return Err(e);
            }
            bytes = &bytes[k as usize..];
        }
        Ok(())
    }
}
