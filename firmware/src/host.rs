//! The few semihosting calls the firmware needs beyond printing: its command
//! line and reading a host file. Semihosting traps to the debugger or to
//! QEMU, which performs the call on the host.

use cortex_m_semihosting::{nr, syscall};

/// The command line the host passed (`-semihosting-config arg=…`), with the
/// program name first, as space-separated words in `buf`.
pub fn cmdline(buf: &mut [u8]) -> Option<&str> {
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: GET_CMDLINE writes at most `block[1]` bytes into `block[0]`,
    // which is `buf`, and stores the length written back into `block[1]`;
    // `block` is passed by address and outlives the call.
    let r = unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if r != 0 {
        return None;
    }
    let len = block.get(1).copied().unwrap_or(0).min(buf.len());
    core::str::from_utf8(buf.get(..len)?).ok()
}

/// A host file opened for reading.
pub struct HostFile {
    fd: usize,
}

impl HostFile {
    /// Opens `path` (relative to QEMU's working folder) for binary reading.
    pub fn open(path: &str) -> Option<Self> {
        // The call wants a NUL-terminated name plus its length without the NUL.
        let mut name = [0u8; 256];
        let bytes = path.as_bytes();
        name.get_mut(..bytes.len())?.copy_from_slice(bytes);
        // SAFETY: `name` outlives the call and is NUL-terminated within bounds.
        let fd = unsafe { syscall!(OPEN, name.as_ptr(), nr::open::R_BINARY, bytes.len()) } as isize;
        (fd >= 0).then_some(HostFile { fd: fd as usize })
    }

    /// Fills `buf` completely; `false` if the file ends first.
    pub fn read_exact(&mut self, buf: &mut [u8]) -> bool {
        // SAFETY: READ writes at most `buf.len()` bytes into `buf` and returns
        // how many it did NOT read.
        let not_read = unsafe { syscall!(READ, self.fd, buf.as_mut_ptr(), buf.len()) };
        not_read == 0
    }
}

impl Drop for HostFile {
    fn drop(&mut self) {
        // SAFETY: closes the descriptor this value owns.
        unsafe {
            syscall!(CLOSE, self.fd);
        }
    }
}
