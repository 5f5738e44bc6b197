//! The fuzz targets as plain, deterministic tests (stable toolchain, no libFuzzer): every
//! committed input under `corpus/<target>/` (the seeds and whatever libFuzzer saved there),
//! then pseudo-random inputs (mutated seeds and uniform bytes) from a fixed seed.
//!
//! `WALK_FUZZ_CASES` sets the number of random inputs per target (default 2000 / 200).

use std::path::Path;

fn xorshift(state: &mut u64) -> u64 {
    let mut x = *state;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    *state = x;
    x
}

fn corpus(target: &str) -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("corpus")
        .join(target);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

fn cases(default: usize) -> usize {
    std::env::var("WALK_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Random inputs: half mutations of corpus entries (byte flips, insertions, truncations), half
/// uniform bytes.
fn random_inputs(seeds: &[Vec<u8>], n: usize, max_len: usize, seed: u64) -> Vec<Vec<u8>> {
    let mut s = seed;
    (0..n)
        .map(|i| {
            if i % 2 == 0 && !seeds.is_empty() {
                let mut v = seeds[(xorshift(&mut s) as usize) % seeds.len()].clone();
                for _ in 0..1 + xorshift(&mut s) % 4 {
                    let r = xorshift(&mut s);
                    match r % 3 {
                        0 if !v.is_empty() => {
                            let k = (r >> 8) as usize % v.len();
                            v[k] ^= 1 << ((r >> 40) % 8);
                        }
                        1 => {
                            let k = (r >> 8) as usize % (v.len() + 1);
                            v.insert(k, (r >> 32) as u8);
                        }
                        _ => {
                            let k = (r >> 8) as usize % (v.len() + 1);
                            v.truncate(k);
                        }
                    }
                }
                v
            } else {
                let len = (xorshift(&mut s) as usize) % max_len;
                (0..len).map(|_| xorshift(&mut s) as u8).collect()
            }
        })
        .collect()
}

#[test]
fn seed_corpus_is_up_to_date_and_valid() {
    for (target, name, bytes) in walk_fuzz::seeds() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("corpus")
            .join(target)
            .join(&name);
        if std::env::var_os("WALK_FUZZ_WRITE_SEEDS").is_some() {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &bytes).unwrap();
        }
        let on_disk = std::fs::read(&path)
            .unwrap_or_else(|e| panic!("{}: {e} (WALK_FUZZ_WRITE_SEEDS=1)", path.display()));
        assert_eq!(on_disk, bytes, "{target}/{name}");
    }
}

#[test]
fn decode_over_corpus_and_random_frames() {
    let seeds = corpus("decode");
    assert!(seeds.len() >= 8);
    for input in &seeds {
        walk_fuzz::decode_one(input);
    }
    for input in random_inputs(&seeds, cases(20_000), 12, 0x5EED_DEC0) {
        walk_fuzz::decode_one(&input);
    }
    // Exhaustive over the command identifiers' lengths and first bytes.
    for id in [0x010u16, 0x020, 0x100, 0x101] {
        for len in 0..=8usize {
            for b in 0..=255u8 {
                let mut v = id.to_le_bytes().to_vec();
                v.extend((0..len).map(|i| b.wrapping_mul(i as u8 + 1)));
                walk_fuzz::decode_one(&v);
            }
        }
    }
}

#[test]
fn node_over_corpus_and_random_programs() {
    let seeds = corpus("node");
    assert!(seeds.len() >= 4);
    for input in &seeds {
        walk_fuzz::node_run(input);
    }
    for input in random_inputs(&seeds, cases(300), 200, 0x5EED_0DE0) {
        walk_fuzz::node_run(&input);
    }
}

#[test]
fn wlog_over_corpus_and_random_files() {
    let seeds = corpus("wlog");
    assert!(seeds.len() >= 3);
    for input in &seeds {
        walk_fuzz::wlog_one(input);
    }
    for input in random_inputs(&seeds, cases(20_000), 300, 0x5EED_1067) {
        walk_fuzz::wlog_one(&input);
    }
}

#[test]
fn text_over_corpus_and_random_texts() {
    let seeds = corpus("text");
    assert!(seeds.len() >= 5);
    for input in &seeds {
        walk_fuzz::text_one(input);
    }
    for input in random_inputs(&seeds, cases(2_000), 200, 0x5EED_7E47) {
        walk_fuzz::text_one(&input);
    }
}
