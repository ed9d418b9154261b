//! Seeded mutation smoke test of the Design parser and the share-link decoder (stable Rust;
//! `fuzz/fuzz_targets/share_decode.rs` is the coverage-guided version). Any input must give a
//! design or a typed error, never a panic.

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use weft::design::share;
use weft::Design;

fn seeds() -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut out: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    out.sort();
    out
}

fn mutate(rng: &mut Pcg64, bytes: &mut Vec<u8>) {
    if bytes.is_empty() {
        bytes.push(b'{');
    }
    let i = (rng.next_u64() as usize) % bytes.len();
    match rng.next_u32() % 6 {
        0 => bytes[i] ^= 1 << (rng.next_u32() % 8),
        1 => bytes.truncate(i),
        2 => bytes.insert(i, b"{}[]\",:0123456789.-eE"[(rng.next_u32() % 21) as usize]),
        3 => {
            let n = (rng.next_u64() as usize % 16).min(bytes.len() - i);
            let chunk = bytes[i..i + n].to_vec();
            bytes.splice(i..i, chunk);
        }
        4 => bytes.splice(i..i, b"1e308".iter().copied()).for_each(drop),
        _ => {
            bytes.remove(i);
        }
    }
}

#[test]
fn mutated_designs_and_links_never_panic() {
    let mut rng = Pcg64::seed_from_u64(0x5eed);
    let rounds: usize = std::env::var("WEFT_FUZZ_ROUNDS").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let mut accepted = 0;
    for seed in seeds() {
        let link = share::encode(&Design::from_json("seed", &seed).unwrap(), &[]).fragment;
        for _ in 0..200 * rounds {
            let mut bytes = seed.clone().into_bytes();
            for _ in 0..1 + rng.next_u32() % 4 {
                mutate(&mut rng, &mut bytes);
            }
            if let Ok(d) = Design::from_json("fuzz", &String::from_utf8_lossy(&bytes)) {
                accepted += 1;
                // A design that parses also validates and round-trips.
                assert!(d.validate().is_empty());
                assert_eq!(Design::from_json("again", &d.to_json_pretty()).unwrap(), d);
            }
            let mut frag = link.clone().into_bytes();
            mutate(&mut rng, &mut frag);
            let _ = share::decode(&String::from_utf8_lossy(&frag));
        }
    }
    assert!(accepted > 0, "no mutated design parsed: the mutations are too destructive to test acceptance");
}
