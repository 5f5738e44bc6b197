//! The CAN frames decoded by name with the DBC file (`host-sim/can/walking.dbc`, compiled in):
//! each frame's message name and its signals in physical units, as CAN tools show them. The
//! MCAP file's `/can` channel and the live view carry them.
//!
//! Every signal of the file is little-endian (Intel); a signal's raw value is its `size` bits
//! from `start_bit` of the 64-bit little-endian data word, sign-extended if signed, then
//! `raw · factor + offset`.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use can_dbc::{ByteOrder, Dbc, MessageId, ValueType};

/// The DBC file shipped with host-sim.
pub const WALKING_DBC: &str = include_str!("../../can/walking.dbc");

fn dbc() -> Option<&'static Dbc> {
    static DBC: OnceLock<Option<Dbc>> = OnceLock::new();
    DBC.get_or_init(|| Dbc::try_from(WALKING_DBC).ok()).as_ref()
}

/// The frame's message name and signals, `None` for an identifier the DBC does not name (or a
/// length other than the message's).
pub fn decode(id: u16, data: &[u8]) -> Option<(String, BTreeMap<String, f64>)> {
    let msg = dbc()?
        .messages
        .iter()
        .find(|m| m.id == MessageId::Standard(id))?;
    if msg.size != data.len() as u64 {
        return None;
    }
    let mut word = [0u8; 8];
    word[..data.len()].copy_from_slice(data);
    let bits = u64::from_le_bytes(word);
    let mut signals = BTreeMap::new();
    for s in &msg.signals {
        if s.byte_order != ByteOrder::LittleEndian || s.size == 0 || s.size > 64 {
            continue;
        }
        let mask = if s.size == 64 {
            u64::MAX
        } else {
            (1u64 << s.size) - 1
        };
        let raw = (bits >> s.start_bit) & mask;
        let v = match s.value_type {
            ValueType::Signed => ((raw << (64 - s.size)) as i64 >> (64 - s.size)) as f64,
            ValueType::Unsigned => raw as f64,
        };
        signals.insert(s.name.clone(), v * s.factor + s.offset);
    }
    Some((msg.name.clone(), signals))
}

#[cfg(test)]
mod tests {
    use super::*;
    use planner_core::wire::{Command, ControlOp, Status};

    #[test]
    fn frames_decode_by_name() {
        assert!(dbc().is_some(), "the DBC parses");
        let c = Command::Control {
            session: 3,
            seq: 7,
            op: ControlOp::Start,
        }
        .encode();
        let (name, s) = decode(c.id, c.bytes()).unwrap();
        assert_eq!(name, "CONTROL");
        assert!(s.values().any(|&v| v == 7.0), "{s:?}");
        let st = Status {
            state: 1,
            queue: 4,
            ..Status::default()
        }
        .encode();
        let (name, s) = decode(st.id, st.bytes()).unwrap();
        assert_eq!(name, "STATUS");
        assert!(s.values().any(|&v| v == 4.0), "{s:?}");
        assert!(decode(0x7FF, &[0; 8]).is_none());
    }
}
