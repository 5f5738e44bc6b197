//! The compact binary CAN log that the QEMU image replays (the decoder; the encoder is
//! host-side, `host_sim::replay::binary_log`).
//!
//! A file is a sequence of logs, each a header and its frames; the file ends where a header
//! would begin. Little endian throughout:
//!
//! ```text
//! log     := header frame{count}
//! header  := "WLOG" version:u8 (= 1) name_len:u8 (≤ 32) name:[u8; name_len] (ASCII graphic)
//!            period_us:u32 (≥ 2) first_us:u64 last_us:u64 count:u32
//!            left_x left_y left_yaw right_x right_y right_yaw: f64 each (finite)
//! frame   := dt_us:ULEB128 (≤ 10 bytes, fits a u64) id:u16 (≤ 0x7FF) len:u8 (≤ 8) data:[u8; len]
//! ```
//!
//! * `first_us` is the time of the recorded log's first line (the node's frames included: the
//!   replay's cycle grid starts there, `planner_core::playback::LogClock::new`); the first
//!   frame's `dt_us` counts from it, every other frame's from the frame before it;
//! * the frames are the ones to replay (a candump log without the frames the node sends
//!   itself), in log order; `last_us` is the time of the last one (`first_us` if there is
//!   none): every frame's time is at most `last_us` and the last one's is exactly it, so that
//!   [`Player::new`](crate::player::Player::new) can be given it before the frames are read;
//! * the feet are where the node stands at start-up (the run's `NodeConfig::left`, `right`).
//!
//! Decoding is validated and panic-free: any input gives frames that satisfy the above, then
//! at most one [`Error`] (and the fuzz target `wlog` of `fuzz/` checks it).

use planner_core::gait::{Footstep, Side};
use planner_core::wire::RawFrame;

use crate::player::{LogFrame, Source};

/// The first four bytes of every log.
pub const MAGIC: [u8; 4] = *b"WLOG";
/// The format's version.
pub const VERSION: u8 = 1;
/// Longest name of a log \[bytes\].
pub const NAME_MAX: usize = 32;

/// Where the decoder reads bytes from.
pub trait Bytes {
    /// The next byte; `None` at the end of the input (or if it cannot be read).
    fn byte(&mut self) -> Option<u8>;
}

/// A byte slice as [`Bytes`].
#[derive(Clone, Debug)]
pub struct SliceBytes<'a> {
    rest: &'a [u8],
}

impl<'a> SliceBytes<'a> {
    /// Reads `bytes` from the start.
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { rest: bytes }
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.rest.len()
    }
}

impl Bytes for SliceBytes<'_> {
    fn byte(&mut self) -> Option<u8> {
        let (&b, rest) = self.rest.split_first()?;
        self.rest = rest;
        Some(b)
    }
}

/// Why a log was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error {
    /// The input ended inside a header or a frame.
    Truncated,
    /// A header does not start with [`MAGIC`].
    Magic,
    /// A version other than [`VERSION`].
    Version(u8),
    /// A name longer than [`NAME_MAX`] or with a byte that is not ASCII graphic.
    Name,
    /// A control period below 2 µs.
    Period,
    /// `last_us` before `first_us`, or not `first_us` in a log without frames.
    Last,
    /// A foot coordinate that is not finite.
    Feet,
    /// A time increment longer than 10 bytes or beyond `u64`.
    Delta,
    /// A frame time beyond `last_us`, or the last frame's time not `last_us`.
    Time,
    /// An identifier above 0x7FF.
    Id(u16),
    /// More than 8 data bytes.
    Length(u8),
}

/// A log's header.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Header {
    name: [u8; NAME_MAX],
    name_len: u8,
    /// The control period \[µs\].
    pub period_us: u32,
    /// The time of the recorded log's first line \[µs\].
    pub first_us: u64,
    /// The time of the last frame \[µs\] (`first_us` if there is none).
    pub last_us: u64,
    /// Frames in the log.
    pub count: u32,
    /// Where the left and the right foot stand at start-up.
    pub feet: [Footstep<f64>; 2],
}

fn take<B: Bytes, const N: usize>(src: &mut B) -> Result<[u8; N], Error> {
    let mut out = [0u8; N];
    for b in out.iter_mut() {
        *b = src.byte().ok_or(Error::Truncated)?;
    }
    Ok(out)
}

fn f64_at<B: Bytes>(src: &mut B) -> Result<f64, Error> {
    let v = f64::from_le_bytes(take(src)?);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::Feet)
    }
}

impl Header {
    /// Reads the next header: `Ok(None)` if the input ends before its first byte (the end of
    /// the file).
    pub fn read<B: Bytes>(src: &mut B) -> Result<Option<Header>, Error> {
        let Some(m0) = src.byte() else {
            return Ok(None);
        };
        let [m1, m2, m3] = take(src)?;
        if [m0, m1, m2, m3] != MAGIC {
            return Err(Error::Magic);
        }
        let [version] = take(src)?;
        if version != VERSION {
            return Err(Error::Version(version));
        }
        let [name_len] = take(src)?;
        if usize::from(name_len) > NAME_MAX {
            return Err(Error::Name);
        }
        let mut name = [0u8; NAME_MAX];
        for b in name.iter_mut().take(usize::from(name_len)) {
            *b = src.byte().ok_or(Error::Truncated)?;
            if !b.is_ascii_graphic() {
                return Err(Error::Name);
            }
        }
        let period_us = u32::from_le_bytes(take(src)?);
        if period_us < 2 {
            return Err(Error::Period);
        }
        let first_us = u64::from_le_bytes(take(src)?);
        let last_us = u64::from_le_bytes(take(src)?);
        let count = u32::from_le_bytes(take(src)?);
        if last_us < first_us || (count == 0 && last_us != first_us) {
            return Err(Error::Last);
        }
        let mut foot = |side| -> Result<Footstep<f64>, Error> {
            let x = f64_at(src)?;
            let y = f64_at(src)?;
            let yaw = f64_at(src)?;
            Ok(Footstep::new(side, x, y, yaw))
        };
        let feet = [foot(Side::Left)?, foot(Side::Right)?];
        Ok(Some(Header {
            name,
            name_len,
            period_us,
            first_us,
            last_us,
            count,
            feet,
        }))
    }

    /// The log's name (ASCII graphic, at most [`NAME_MAX`] bytes).
    pub fn name(&self) -> &str {
        let bytes = self.name.get(..usize::from(self.name_len)).unwrap_or(&[]);
        // Checked ASCII when read.
        core::str::from_utf8(bytes).unwrap_or("?")
    }
}

fn uleb128<B: Bytes>(src: &mut B) -> Result<u64, Error> {
    let mut v = 0u64;
    for i in 0..10u32 {
        let b = src.byte().ok_or(Error::Truncated)?;
        let low = u64::from(b & 0x7F);
        // The tenth byte holds bit 63 only.
        if i == 9 && low > 1 {
            return Err(Error::Delta);
        }
        v |= low << (7 * i);
        if b & 0x80 == 0 {
            return Ok(v);
        }
    }
    Err(Error::Delta)
}

/// The frames of one log, read after its [`Header`]: a [`Source`] for the
/// [`Player`](crate::player::Player). After the last frame, or at the first error, it gives
/// no more frames; [`Frames::error`] tells which.
#[derive(Debug)]
pub struct Frames<'a, B: Bytes> {
    src: &'a mut B,
    remaining: u32,
    t_us: u64,
    last_us: u64,
    error: Option<Error>,
}

impl<'a, B: Bytes> Frames<'a, B> {
    /// The frames announced by `header`, read from `src` (positioned after the header).
    pub fn new(header: &Header, src: &'a mut B) -> Self {
        Self {
            src,
            remaining: header.count,
            t_us: header.first_us,
            last_us: header.last_us,
            error: None,
        }
    }

    /// Frames not read yet.
    pub fn remaining(&self) -> u32 {
        self.remaining
    }

    /// Why the log was refused, if it was.
    pub fn error(&self) -> Option<Error> {
        self.error
    }

    /// Reads the frames that were not read (to reach the next header); stops at an error.
    pub fn skip_rest(&mut self) -> Result<(), Error> {
        while self.next_frame().is_some() {}
        self.error.map_or(Ok(()), Err)
    }

    fn read(&mut self) -> Result<LogFrame, Error> {
        let dt = uleb128(self.src)?;
        let us = self.t_us.checked_add(dt).ok_or(Error::Delta)?;
        let last = self.remaining == 1;
        if us > self.last_us || (last && us != self.last_us) {
            return Err(Error::Time);
        }
        let id = u16::from_le_bytes(take(self.src)?);
        if id > 0x7FF {
            return Err(Error::Id(id));
        }
        let [len] = take(self.src)?;
        if len > 8 {
            return Err(Error::Length(len));
        }
        let mut data = [0u8; 8];
        for b in data.iter_mut().take(usize::from(len)) {
            *b = self.src.byte().ok_or(Error::Truncated)?;
        }
        let frame = RawFrame::new(id, data.get(..usize::from(len)).unwrap_or(&[]))
            .ok_or(Error::Length(len))?;
        self.t_us = us;
        Ok(LogFrame { us, frame })
    }
}

impl<B: Bytes> Source for Frames<'_, B> {
    fn next_frame(&mut self) -> Option<LogFrame> {
        if self.remaining == 0 || self.error.is_some() {
            return None;
        }
        match self.read() {
            Ok(f) => {
                self.remaining -= 1;
                Some(f)
            }
            Err(e) => {
                self.error = Some(e);
                None
            }
        }
    }
}
