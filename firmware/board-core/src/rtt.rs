//! The never-blocking part of the board's RTT logger (`firmware/board/src/logger.rs`): a log
//! frame is staged whole, then copied into the RTT ring only if it fits, so that the loop never
//! waits for the host and the host never reads a torn frame.

/// A log frame being built, at most `N` bytes (a longer one is marked and then dropped).
#[derive(Clone, Debug)]
pub struct Stage<const N: usize> {
    buf: [u8; N],
    len: usize,
    overflow: bool,
}

impl<const N: usize> Default for Stage<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Stage<N> {
    /// Empty.
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            len: 0,
            overflow: false,
        }
    }

    /// Starts a new frame.
    pub fn clear(&mut self) {
        self.len = 0;
        self.overflow = false;
    }

    /// Appends bytes (beyond `N`, the frame is marked as too long).
    pub fn push(&mut self, bytes: &[u8]) {
        for &b in bytes {
            match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = b;
                    self.len += 1;
                }
                None => self.overflow = true,
            }
        }
    }

    /// The frame, `None` if it was too long.
    pub fn frame(&self) -> Option<&[u8]> {
        if self.overflow {
            return None;
        }
        self.buf.get(..self.len)
    }
}

/// Bytes free in a ring of `size` with the reader at `read` and the writer at `write` (one byte
/// always stays free, to tell a full ring from an empty one). Offsets are taken modulo `size`
/// (a probe could write anything there).
pub fn free(size: usize, read: usize, write: usize) -> usize {
    if size == 0 {
        return 0;
    }
    let (read, write) = (read % size, write % size);
    (read + size - write - 1) % size
}

/// Copies `frame` into `ring` from `write` on, wrapping, if it fits whole before `read`;
/// the new write offset, or `None` (nothing written) if it does not fit.
pub fn commit(ring: &mut [u8], read: usize, write: usize, frame: &[u8]) -> Option<usize> {
    let size = ring.len();
    if size == 0 {
        return frame.is_empty().then_some(0);
    }
    if frame.len() > free(size, read, write) {
        return None;
    }
    let mut at = write % size;
    for &b in frame {
        if let Some(slot) = ring.get_mut(at) {
            *slot = b;
        }
        at = (at + 1) % size;
    }
    Some(at)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_goes_in_whole_or_not_at_all() {
        let mut ring = [0u8; 8];
        // Empty ring: 7 bytes free.
        assert_eq!(free(8, 0, 0), 7);
        assert_eq!(commit(&mut ring, 0, 0, &[1; 8]), None);
        assert_eq!(ring, [0; 8], "nothing written when it does not fit");
        assert_eq!(commit(&mut ring, 0, 0, &[1, 2, 3]), Some(3));
        assert_eq!(&ring[..3], &[1, 2, 3]);
        // The reader took 2 bytes; 5 + 1 more fit, wrapping.
        assert_eq!(free(8, 2, 3), 6);
        assert_eq!(commit(&mut ring, 2, 3, &[4, 5, 6, 7, 8, 9]), Some(1));
        assert_eq!(ring, [9, 2, 3, 4, 5, 6, 7, 8]);
        // Full now (one byte kept free): nothing more until the reader moves.
        assert_eq!(free(8, 2, 1), 0);
        assert_eq!(commit(&mut ring, 2, 1, &[0xAA]), None);
    }

    #[test]
    fn garbage_offsets_are_taken_modulo_the_size() {
        let mut ring = [0u8; 4];
        assert_eq!(free(4, 9, 13), 3);
        assert_eq!(commit(&mut ring, 9, 13, &[7]), Some(2));
        assert_eq!(ring[1], 7);
        assert_eq!(free(0, 0, 0), 0);
        assert_eq!(commit(&mut [], 0, 0, &[1]), None);
        assert_eq!(commit(&mut [], 0, 0, &[]), Some(0));
    }

    #[test]
    fn a_stage_marks_a_frame_too_long() {
        let mut s = Stage::<4>::new();
        s.push(&[1, 2]);
        s.push(&[3]);
        assert_eq!(s.frame(), Some(&[1, 2, 3][..]));
        s.push(&[4, 5]);
        assert_eq!(s.frame(), None);
        s.clear();
        assert_eq!(s.frame(), Some(&[][..]));
    }
}
