//! Reading a host file over semihosting (`SYS_OPEN`, `SYS_FLEN`, `SYS_READ`, `SYS_CLOSE`),
//! buffered, as [`gait_loop::binlog::Bytes`], and the image's command line
//! (`SYS_GET_CMDLINE`: QEMU's `-append`).
//!
//! The one `unsafe` item is [`call`]: the semihosting trap with a parameter block that
//! borrows what the host reads or writes.

use cortex_m_semihosting::nr;
use gait_loop::binlog::Bytes;

/// A semihosting operation and what its parameter block points to.
enum Call<'a> {
    /// `SYS_OPEN`: a NUL-terminated name (the length passed excludes the NUL), a mode.
    Open(&'a [u8], usize),
    /// `SYS_FLEN`: the file's length.
    Flen(usize),
    /// `SYS_READ`: up to `buf.len()` bytes into `buf`; returns the number NOT read.
    Read(usize, &'a mut [u8]),
    /// `SYS_CLOSE`.
    Close(usize),
    /// `SYS_GET_CMDLINE`: the command line into `buf`, NUL-terminated (the host also writes
    /// its length into the parameter block).
    Cmdline(&'a mut [u8]),
}

/// Runs one semihosting operation; the host's return value (`usize::MAX` is -1, an error).
#[allow(unsafe_code)]
fn call(c: Call<'_>) -> usize {
    let (op, mut block): (usize, [usize; 3]) = match c {
        Call::Open(name, mode) => {
            // A name without its NUL would make the host read past the slice.
            if name.last() != Some(&0) {
                return usize::MAX;
            }
            (nr::OPEN, [name.as_ptr() as usize, mode, name.len() - 1])
        }
        Call::Flen(fd) => (nr::FLEN, [fd, 0, 0]),
        Call::Read(fd, buf) => (nr::READ, [fd, buf.as_mut_ptr() as usize, buf.len()]),
        Call::Close(fd) => (nr::CLOSE, [fd, 0, 0]),
        Call::Cmdline(buf) => (nr::GET_CMDLINE, [buf.as_mut_ptr() as usize, buf.len(), 0]),
    };
    // SAFETY: `block` is the operation's parameter block (ARM semihosting specification: OPEN
    // takes name pointer, mode, name length; FLEN and CLOSE a handle; READ handle, buffer,
    // length; GET_CMDLINE buffer, length, and writes the length used back into the block).
    // Every pointer in it comes from a borrow held for this call (`Call<'_>`): the host reads
    // the name up to its NUL, checked present above, and writes at most `buf.len()` bytes into
    // the exclusively borrowed `buf`, and into the block itself, which is passed by a pointer
    // from a mutable borrow. The host touches no other memory, and the trap returns before
    // the borrows end.
    unsafe { cortex_m_semihosting::syscall1(op, block.as_mut_ptr() as usize) }
}

/// Whether `word` is one of the words of the image's command line (QEMU: the `-kernel` path
/// and the `-append` text, space-separated); `false` if the host gives none.
pub fn cmdline_has(word: &str) -> bool {
    let mut buf = [0u8; 256];
    if call(Call::Cmdline(&mut buf)) != 0 {
        return false;
    }
    let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    buf[..end]
        .split(|&b| b == b' ')
        .any(|w| w == word.as_bytes())
}

/// A host file opened for reading in binary mode, read through a buffer.
pub struct HostFile {
    fd: usize,
    len: usize,
    buf: [u8; 512],
    at: usize,
    filled: usize,
    /// The host refused a read.
    failed: bool,
}

impl HostFile {
    /// Opens `name` (NUL-terminated, relative to QEMU's working directory); `None` if the host
    /// cannot open it or tell its length.
    pub fn open(name: &[u8]) -> Option<HostFile> {
        let fd = call(Call::Open(name, nr::open::R_BINARY));
        if fd == usize::MAX {
            return None;
        }
        let len = call(Call::Flen(fd));
        if len == usize::MAX {
            call(Call::Close(fd));
            return None;
        }
        Some(HostFile {
            fd,
            len,
            buf: [0; 512],
            at: 0,
            filled: 0,
            failed: false,
        })
    }

    /// The file's length \[bytes\] (`SYS_FLEN`).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether a read failed (the input then ends there).
    pub fn failed(&self) -> bool {
        self.failed
    }

    fn refill(&mut self) -> bool {
        if self.failed {
            return false;
        }
        let not_read = call(Call::Read(self.fd, &mut self.buf));
        if not_read > self.buf.len() {
            self.failed = true;
            return false;
        }
        self.at = 0;
        self.filled = self.buf.len() - not_read;
        self.filled > 0
    }
}

impl Bytes for HostFile {
    fn byte(&mut self) -> Option<u8> {
        if self.at >= self.filled && !self.refill() {
            return None;
        }
        let b = self.buf.get(self.at).copied();
        self.at += 1;
        b
    }
}

impl Drop for HostFile {
    fn drop(&mut self) {
        call(Call::Close(self.fd));
    }
}
