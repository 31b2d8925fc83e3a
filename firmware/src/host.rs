//! The few semihosting calls the firmware needs beyond printing: its command
//! line and reading a host file. Semihosting traps to the debugger or to
//! QEMU, which performs the call on the host.

use cortex_m_semihosting::{nr, syscall};

/// The command line the host passed (`-semihosting-config arg=…`), with the
/// program name first, as space-separated words in `buf`.
fn cmdline(buf: &mut [u8]) -> Option<&str> {
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

/// The firmware's command line, `FIXTURE [SEED [EXTRA]]`.
pub struct Args<'a> {
    /// The fixture's path, or the caller's default.
    pub path: &'a str,
    /// The tracker's seed, 1 if not given.
    pub seed: u64,
    /// A third word, if any.
    pub extra: Option<&'a str>,
}

/// Parses the command line into `buf`; the error says what is wrong.
pub fn args<'a>(buf: &'a mut [u8], default_path: &'a str) -> Result<Args<'a>, &'static str> {
    let line = cmdline(buf).unwrap_or("");
    let mut words = line.split_ascii_whitespace().skip(1);
    let path = words.next().unwrap_or(default_path);
    let seed = match words.next().map(str::parse) {
        None => 1,
        Some(Ok(s)) => s,
        Some(Err(_)) => return Err("seed is not a number"),
    };
    Ok(Args { path, seed, extra: words.next() })
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

    /// Reads into `buf` until it is full or the file ends; returns the
    /// bytes read.
    pub fn read(&mut self, buf: &mut [u8]) -> usize {
        // SAFETY: READ writes at most `buf.len()` bytes into `buf` and returns
        // how many it did NOT read.
        let not_read = unsafe { syscall!(READ, self.fd, buf.as_mut_ptr(), buf.len()) };
        buf.len().saturating_sub(not_read)
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

/// Why a fixture could not be streamed.
pub enum StreamError {
    /// The host could not open the file.
    Open,
    /// The header or a record is malformed, or the file ends early.
    Fixture(pftrack_fixture::FixtureError),
}

impl core::fmt::Display for StreamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StreamError::Open => f.write_str("cannot open"),
            StreamError::Fixture(e) => write!(f, "{e}"),
        }
    }
}

/// A `.pft` fixture read from the host one frame at a time, so that memory
/// does not grow with its length.
pub struct FixtureStream {
    file: HostFile,
    /// The fixture's header.
    pub header: pftrack_fixture::Header,
}

impl FixtureStream {
    /// Opens `path` and reads its header.
    pub fn open(path: &str) -> Result<Self, StreamError> {
        use pftrack_fixture::{FixtureError, HEADER_LEN, Header};
        let mut file = HostFile::open(path).ok_or(StreamError::Open)?;
        let mut bytes = [0u8; HEADER_LEN];
        let len = file.read(&mut bytes);
        if len < HEADER_LEN {
            return Err(StreamError::Fixture(FixtureError::TruncatedHeader { len }));
        }
        let header = Header::parse(&bytes).map_err(StreamError::Fixture)?;
        Ok(FixtureStream { file, header })
    }

    /// Reads frame `index` (the next one) into `pixels`, which must hold
    /// `header.frame_len()` bytes, and returns its first target's ground
    /// truth and visibility; the other targets' truths of a fixture with
    /// several go into `others` (which must hold `header.targets - 1`).
    pub fn next(
        &mut self,
        index: u32,
        pixels: &mut [u8],
        others: &mut [pftrack::BoundingBox],
    ) -> Result<pftrack_fixture::RecordMeta, StreamError> {
        use pftrack_fixture::{FixtureError, RECORD_META_LEN, RecordMeta};
        let expected_len = self.header.record_len();
        let truncated =
            |got| StreamError::Fixture(FixtureError::TruncatedFrame { index, expected_len, actual_len: got });
        let mut meta = [0u8; RECORD_META_LEN];
        let mut got = self.file.read(&mut meta);
        if got < RECORD_META_LEN {
            return Err(truncated(got));
        }
        let first = RecordMeta::parse(&meta, index).map_err(StreamError::Fixture)?;
        for k in 1..self.header.targets as usize {
            let mut m = [0u8; RECORD_META_LEN];
            let n = self.file.read(&mut m);
            got += n;
            if n < RECORD_META_LEN {
                return Err(truncated(got));
            }
            let truth = RecordMeta::parse(&m, index).map_err(StreamError::Fixture)?.truth;
            if let Some(o) = others.get_mut(k - 1) {
                *o = truth;
            }
        }
        got += self.file.read(pixels);
        if got < RECORD_META_LEN * self.header.targets as usize + pixels.len() {
            return Err(truncated(got));
        }
        Ok(first)
    }
}
