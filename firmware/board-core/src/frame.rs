//! The classic CAN frame of the adapter, and the M_CAN message-RAM element format
//! (RM0433 §56.4.18: 2 header words and, with 8-byte elements, 2 data words).

use embedded_can::{Frame, Id, StandardId};

/// A classic CAN data frame with a standard identifier (the node's whole message set).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClassicFrame {
    id: StandardId,
    len: u8,
    data: [u8; 8],
}

impl ClassicFrame {
    /// The raw 11-bit identifier.
    pub fn raw_id(&self) -> u16 {
        self.id.as_raw()
    }

    /// The frame as a message-RAM TX buffer element (8-byte data field): T0 = standard id in
    /// bits 28:18 (XTD = RTR = ESI = 0), T1 = DLC in bits 19:16 (classic: FDF = BRS = 0, no
    /// event, marker 0), then the data bytes little-endian.
    pub fn to_element(&self) -> [u32; 4] {
        let d = self.data;
        [
            u32::from(self.id.as_raw()) << 18,
            u32::from(self.len) << 16,
            u32::from_le_bytes([d[0], d[1], d[2], d[3]]),
            u32::from_le_bytes([d[4], d[5], d[6], d[7]]),
        ]
    }

    /// `true` if [`from_element`](Self::from_element) takes the element (a classic standard
    /// data frame of at most 8 bytes), without building the frame.
    pub fn is_classic(e: &[u32; 4]) -> bool {
        let [r0, r1, _, _] = *e;
        r0 & (0b11 << 29) == 0 && r1 & (1 << 21) == 0
    }

    /// A message-RAM RX FIFO element as a frame; `None` for what is not a classic standard
    /// data frame (extended id: R0 bit 30, remote: bit 29, FD: R1 bit 21). A classic frame's
    /// DLC of 9 … 15 means 8 data bytes (ISO 11898-1): such a frame is the 8-byte frame.
    pub fn from_element(e: &[u32; 4]) -> Option<Self> {
        let [r0, r1, d0, d1] = *e;
        let extended = r0 & (1 << 30) != 0;
        let remote = r0 & (1 << 29) != 0;
        let fd = r1 & (1 << 21) != 0;
        let dlc = (((r1 >> 16) & 0xF) as u8).min(8);
        if extended || remote || fd {
            return None;
        }
        let id = StandardId::new(((r0 >> 18) & 0x7FF) as u16)?;
        let [a, b, c, d] = d0.to_le_bytes();
        let [e, f, g, h] = d1.to_le_bytes();
        let mut data = [a, b, c, d, e, f, g, h];
        // Bytes beyond the DLC are not the frame's.
        for (i, byte) in data.iter_mut().enumerate() {
            if i >= usize::from(dlc) {
                *byte = 0;
            }
        }
        Some(Self { id, len: dlc, data })
    }
}

impl Frame for ClassicFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        let Id::Standard(id) = id.into() else {
            return None;
        };
        if data.len() > 8 {
            return None;
        }
        // All 8 bytes: a full frame (every stream frame) as one 8-byte copy, a shorter one
        // byte by byte, each taken or zero (a fixed-length loop, as planner-core's
        // `RawFrame::new`: no copy loop of a length known only here).
        let buf: [u8; 8] = match <[u8; 8]>::try_from(data) {
            Ok(full) => full,
            Err(_) => core::array::from_fn(|i| data.get(i).copied().unwrap_or(0)),
        };
        Some(Self {
            id,
            len: data.len() as u8,
            data: buf,
        })
    }

    /// Remote frames are not part of the message set.
    fn new_remote(_id: impl Into<Id>, _dlc: usize) -> Option<Self> {
        None
    }

    fn is_extended(&self) -> bool {
        false
    }

    fn is_remote_frame(&self) -> bool {
        false
    }

    fn id(&self) -> Id {
        Id::Standard(self.id)
    }

    fn dlc(&self) -> usize {
        usize::from(self.len)
    }

    fn data(&self) -> &[u8] {
        // `len ≤ 8` (checked by `new` and `from_element`); `get` keeps this panic-free.
        self.data.get(..usize::from(self.len)).unwrap_or(&self.data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(id: u16, data: &[u8]) -> ClassicFrame {
        ClassicFrame::new(StandardId::new(id).unwrap(), data).unwrap()
    }

    #[test]
    fn element_round_trip_keeps_id_length_and_data() {
        for (id, data) in [(0x7FF, &[][..]), (0x100, &[1, 2, 3]), (0x010, &[9; 8])] {
            let f = frame(id, data);
            let e = f.to_element();
            assert_eq!(e[0] >> 18, u32::from(id));
            assert_eq!((e[1] >> 16) & 0xF, data.len() as u32);
            assert_eq!(ClassicFrame::from_element(&e), Some(f));
        }
    }

    #[test]
    fn foreign_elements_are_refused_and_bytes_past_the_dlc_dropped() {
        let base = frame(0x100, &[1, 2]).to_element();
        for (word, bit) in [(0, 30), (0, 29), (1, 21)] {
            let mut e = base;
            e[word] |= 1 << bit;
            assert_eq!(
                ClassicFrame::from_element(&e),
                None,
                "bit {bit} of word {word}"
            );
        }
        // A classic frame's DLC 9 … 15 means 8 bytes (in an FD frame, it is an FD length).
        let eight = frame(0x100, &[1, 2, 3, 4, 5, 6, 7, 8]);
        for dlc in 9..16u32 {
            let mut e = eight.to_element();
            e[1] = (e[1] & !(0xF << 16)) | (dlc << 16);
            assert_eq!(ClassicFrame::from_element(&e), Some(eight), "DLC {dlc}");
            e[1] |= 1 << 21;
            assert_eq!(ClassicFrame::from_element(&e), None, "FD, DLC {dlc}");
        }
        // `is_classic` says the same as `from_element`, for every combination of the bits.
        for xtd_rtr in 0..4u32 {
            for fdf in 0..2u32 {
                for dlc in 0..16u32 {
                    let mut e = base;
                    e[0] |= xtd_rtr << 29;
                    e[1] = (e[1] & !(0xF << 16)) | (dlc << 16) | (fdf << 21);
                    assert_eq!(
                        ClassicFrame::is_classic(&e),
                        ClassicFrame::from_element(&e).is_some(),
                        "{e:x?}"
                    );
                }
            }
        }
        let mut e = base;
        e[2] = 0xFFFF_FFFF;
        assert_eq!(
            ClassicFrame::from_element(&e).unwrap().data(),
            &[0xFF, 0xFF]
        );
        assert!(ClassicFrame::new(embedded_can::ExtendedId::ZERO, &[]).is_none());
        assert!(ClassicFrame::new(StandardId::ZERO, &[0; 9]).is_none());
    }
}
