//! Lookups in the gait's footstep queue by id (`position`, `is_queued`, `queued_step`,
//! `previous_feet`, `modify`) against a model of the queue searched front to back, for the id
//! sequences a queue can hold: consecutive 8-bit ids across their wrap (what the node sends),
//! consecutive 16-bit ids across theirs, 255 followed by 256, ids with a gap, repeated ids.
//! Consecutive ids are looked up by arithmetic; the rest by a search; both must give what the
//! search of the model gives, while the queue fills and while walking empties it.

use planner_core::gait::{Footstep, Gait, GaitParams, Side};

type G = Gait<f64, 32>;

fn standing() -> G {
    let mut p = GaitParams::hrp2();
    p.shaping = false;
    Gait::new(
        p,
        Footstep::new(Side::Left, 0.0, 0.1, 0.0),
        Footstep::new(Side::Right, 0.0, -0.1, 0.0),
    )
    .expect("valid gait parameters")
}

/// The model's answer for `previous_feet(before)` when two steps precede it: the last step of
/// each side before the first queued `before` (or before the end).
fn model_previous(
    model: &[(u16, Footstep<f64>)],
    before: Option<u16>,
) -> Option<[Footstep<f64>; 2]> {
    let end = before
        .and_then(|id| model.iter().position(|(i, _)| *i == id))
        .unwrap_or(model.len());
    let mut last: [Option<Footstep<f64>>; 2] = [None, None];
    for (_, s) in &model[..end] {
        last[usize::from(s.side == Side::Right)] = Some(*s);
    }
    Some([last[0]?, last[1]?])
}

/// Every lookup of every id in `probe` agrees with the model.
fn check(g: &G, model: &[(u16, Footstep<f64>)], probe: &[u16], what: &str) {
    assert_eq!(g.queued(), model.len(), "{what}: queue length");
    for &id in probe {
        let first = model.iter().position(|(i, _)| *i == id);
        assert_eq!(g.position(id), first, "{what}: position({id})");
        assert_eq!(g.is_queued(id), first.is_some(), "{what}: is_queued({id})");
        assert_eq!(
            g.queued_step(id),
            first.map(|k| model[k].1),
            "{what}: queued_step({id})"
        );
        if let Some(expected) = model_previous(model, Some(id)) {
            assert_eq!(
                g.previous_feet(Some(id)),
                expected,
                "{what}: previous_feet({id})"
            );
        }
    }
    if let Some(expected) = model_previous(model, None) {
        assert_eq!(
            g.previous_feet(None),
            expected,
            "{what}: previous_feet(None)"
        );
    }
}

#[test]
fn lookups_by_id_match_a_search_of_the_queue() {
    let sequences: [(&str, Vec<u16>); 6] = [
        ("8-bit wrap", (0..24).map(|k| (250 + k) % 256).collect()),
        (
            "16-bit wrap",
            (0..24).map(|k| 65_530_u16.wrapping_add(k)).collect(),
        ),
        ("255 then 256", (0..24).map(|k| 244 + k).collect()),
        ("from 0", (0..24).collect()),
        (
            "a gap",
            (0..24).map(|k| if k < 10 { k } else { k + 3 }).collect(),
        ),
        (
            "repeats",
            (0..24)
                .map(|k| [3, 5, 3, 7, 5, 9][k % 6] + 10 * (k / 12) as u16)
                .collect(),
        ),
    ];
    for (name, ids) in sequences {
        let mut g = standing();
        let mut model: Vec<(u16, Footstep<f64>)> = Vec::new();
        // Ids that are queued, and ids around them that are not.
        let mut probe: Vec<u16> = ids.clone();
        probe.extend([0, 1, 2, 12, 254, 255, 256, 257, 1000, 65_535, 65_529]);
        for (k, &id) in ids.iter().enumerate() {
            let side = if k % 2 == 0 { Side::Right } else { Side::Left };
            let y = if side == Side::Left { 0.1 } else { -0.1 };
            let step = Footstep::new(side, 0.1 * (k + 1) as f64, y, 0.0);
            g.push(id, step).expect("room in the queue");
            model.push((id, step));
            check(&g, &model, &probe, &format!("{name}, {} pushed", k + 1));
        }
        // A modification finds its step as the model does (the first of a repeated id).
        let target = ids[7];
        let k = model.iter().position(|(i, _)| *i == target).unwrap();
        let moved = Footstep::new(model[k].1.side, model[k].1.x + 0.01, model[k].1.y, 0.0);
        // Refused or not (eq. 17 decides while walking; standing it is accepted), the queue
        // must then hold what the model holds.
        if g.modify(target, moved).is_ok() {
            model[k].1 = moved;
        }
        check(&g, &model, &probe, &format!("{name}, modified"));
        // Walk: the queue empties from the front as steps lift off.
        g.start().expect("start");
        for tick in 0..6000 {
            g.tick();
            while g.queued() < model.len() {
                model.remove(0);
            }
            if tick % 7 == 0 {
                check(&g, &model, &probe, &format!("{name}, tick {tick}"));
            }
            if model.is_empty() {
                break;
            }
        }
        assert!(model.is_empty(), "{name}: the walk did not take every step");
        check(&g, &model, &probe, &format!("{name}, walked"));
        // Cleared, then filled again from another id: the lookups follow.
        g.push(40, Footstep::new(Side::Right, 3.0, -0.1, 0.0)).ok();
        g.clear_and_stop();
        model.clear();
        check(&g, &model, &probe, &format!("{name}, cleared"));
    }
}
