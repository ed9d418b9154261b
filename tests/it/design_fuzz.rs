//! Seeded mutation smoke tests of the Design parser, the share-link decoder, `--set` paths and
//! the start/end template expander (stable Rust; `fuzz/fuzz_targets/share_decode.rs` is the
//! coverage-guided version of the decoder). Any input must give a design (or text) or a typed
//! error, never a panic, and stay within the stated limits. A fixed number of iterations
//! (times `WEFT_FUZZ_ROUNDS`).

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use weft::catalog::share;
use weft::gcode::{expand_template, MAX_EXPANDED_BYTES};
use weft::testgen::design as gen;
use weft::Design;

fn rounds() -> usize {
    std::env::var("WEFT_FUZZ_ROUNDS").ok().and_then(|s| s.parse().ok()).unwrap_or(1)
}

fn pick<'a>(rng: &mut Pcg64, items: &[&'a str]) -> &'a str {
    items[(rng.next_u32() as usize) % items.len()]
}

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
    let rounds = rounds();
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

#[test]
fn mutated_links_decode_or_fail_cleanly() {
    let mut rng = Pcg64::seed_from_u64(0x11_4b);
    let mut accepted = 0;
    for seed in seeds() {
        for _ in 0..100 * rounds() {
            // The design inside a well-formed link mutated: the decoder reaches the parser.
            let mut bytes = seed.clone().into_bytes();
            for _ in 0..1 + rng.next_u32() % 4 {
                mutate(&mut rng, &mut bytes);
            }
            if let Ok(d) = share::decode(&format!("#d={}", share::pack(&bytes))) {
                accepted += 1;
                assert!(d.validate().is_empty());
            }
        }
    }
    // Crafted links: inflation bombs of several sizes, mutated, and random base64url text.
    for i in 0..200 * rounds() {
        let mut frag = gen::share_bomb_fragment(64 + (rng.next_u32() as usize % 4000)).into_bytes();
        for _ in 0..i % 3 {
            mutate(&mut rng, &mut frag);
        }
        assert!(share::decode(&String::from_utf8_lossy(&frag)).is_err());
        let alphabet = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_";
        let random: String = (0..rng.next_u32() % 3000).map(|_| alphabet[(rng.next_u32() % 64) as usize] as char).collect();
        assert!(share::decode(&format!("#d={random}")).is_err());
    }
    assert!(accepted > 0, "no mutated link decoded: the mutations are too destructive to test acceptance");
}

#[test]
fn random_set_paths_never_panic() {
    let mut rng = Pcg64::seed_from_u64(0x5e7);
    let keys = [
        "job",
        "slice",
        "printer",
        "material",
        "speeds",
        "name",
        "0",
        "1",
        "7",
        "kind",
        "input",
        "file",
        "files",
        "builtin",
        "bed_size_mm",
        "",
        "a",
        "retraction",
        "length_mm",
        "machine",
        "lattice",
        "overrides",
        "pneumatic",
        "start_gcode",
        "version",
    ];
    let values = [
        "1",
        "-1",
        "1e308",
        "0.1",
        "\"x\"",
        "[]",
        "{}",
        "null",
        "slice",
        "lattice",
        "[[[[",
        "true",
        "{\"file\":{\"name\":\"a.stl\"}}",
        "{\"files\":[\"a\",\"b\"]}",
        "five_axis",
        "{design_name}",
        "a\nb",
    ];
    let mut accepted = 0;
    for seed in seeds() {
        let d = Design::from_json("seed", &seed).unwrap();
        for _ in 0..100 * rounds() {
            let depth = 1 + (rng.next_u32() as usize % 40);
            let path: Vec<&str> = (0..depth).map(|_| pick(&mut rng, &keys)).collect();
            let mut set = vec![format!("{}={}", path.join("."), pick(&mut rng, &values))];
            if rng.next_u32() % 8 == 0 {
                set.push(gen::deep_set_path(1 + rng.next_u32() as usize % 100_000));
            }
            if let Ok(d2) = d.with_overrides(&set) {
                accepted += 1;
                assert!(d2.validate().is_empty());
                assert_eq!(Design::from_json("again", &d2.to_json_pretty()).unwrap(), d2);
            }
        }
    }
    assert!(accepted > 0, "no override applied: the paths are too random to test acceptance");
}

/// The expander before it was made linear, as the reference of what a template means.
fn reference_expand(template: &str, vars: &[(&str, String)]) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = template;
    while let Some(open) = rest.find('{') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let close = match after.find(['}', '\n']) {
            Some(c) if after.as_bytes()[c] == b'}' => c,
            _ => {
                out.push('{');
                rest = after;
                continue;
            }
        };
        let name = &after[..close];
        match vars.iter().find(|(n, _)| *n == name.trim()) {
            Some((_, value)) => out.push_str(value),
            None => return Err(name.to_string()),
        }
        rest = &after[close + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

#[test]
fn random_templates_expand_like_the_reference() {
    let mut rng = Pcg64::seed_from_u64(0x7e3);
    let pieces = ["{", "}", "\n", "{design_name}", "{ bed_temp_c }", "{fan_pwm}", "x", " ", "M104 S", "é", "{{", "}}", "{nope}", ";", "\r\n"];
    let name = "n".repeat(256);
    let vars: Vec<(&str, String)> = vec![("bed_temp_c", "60".into()), ("fan_pwm", "255".into()), ("design_name", name)];
    for i in 0..2000 * rounds() {
        let mut t = String::new();
        for _ in 0..rng.next_u32() % 200 {
            t.push_str(pick(&mut rng, &pieces));
        }
        if i % 50 == 0 {
            t.push_str(&gen::unclosed_braces_template(rng.next_u32() as usize % 4000));
        }
        if i % 97 == 0 {
            t = gen::template_bomb(3000 + rng.next_u32() as usize % 2000);
        }
        match (expand_template(&t, "start_gcode", &vars), reference_expand(&t, &vars)) {
            (Ok(a), Ok(b)) => assert_eq!(a, b, "template {t:?}"),
            (Err(weft::gcode::Error::UnknownPlaceholder { name, .. }), Err(r)) => {
                assert!(r.starts_with(name.trim_end_matches('…')), "{name:?} vs {r:?}")
            }
            (Err(weft::gcode::Error::TemplateTooLarge { bytes, .. }), Ok(b)) => {
                assert!(bytes == b.len() && bytes > MAX_EXPANDED_BYTES)
            }
            (a, b) => panic!("template {t:?}: {a:?} vs reference {b:?}"),
        }
    }
}
