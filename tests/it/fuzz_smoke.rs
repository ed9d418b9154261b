//! Stable-toolchain fuzz smoke test: thousands of seeded, deterministic mutations of every
//! fixture and of small hostile inputs from `weft::testgen::mesh` (bit flips, truncation,
//! insertion, duplicated chunks, odd numbers in text, control bytes near the start, the XML
//! inside 3MF files) must make `read_mesh` and `estimate` return `Ok` or `Err`, never panic
//! or hang; when both succeed the estimate's triangle count must be the one read.
//!
//! The real fuzzers live in `fuzz/` (cargo-fuzz); this runs in plain `cargo test`.

use crate::work::Work;
use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::io::{Cursor, Read, Write};
use std::path::PathBuf;
use weft::import::{estimate, read_mesh, Options};

const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e39",
    "-1e39",
    "3.4028236e38",
    "1e-45",
    "4294967295",
    "4294967296",
    "-2147483649",
    "18446744073709551616",
    "-9223372036854775808",
    "99999999999999999999999",
    "0x10",
    "1e",
    ".",
    "-",
    "",
    "1/2/3",
    "//",
    "1 2",
    "\u{0}",
    "é",
];

fn rand_below(rng: &mut Pcg64, n: usize) -> usize {
    if n == 0 {
        0
    } else {
        (rng.next_u64() % n as u64) as usize
    }
}

/// One random mutation of `data`.
fn mutate(rng: &mut Pcg64, data: &mut Vec<u8>) {
    let len = data.len();
    match rng.next_u32() % 9 {
        8 => {
            // A control byte in the first KiB (the STL text rule allows a few).
            let at = rand_below(rng, len.min(1024) + 1);
            data.insert(at, 1 + (rng.next_u32() % 31) as u8);
        }
        0 => {
            for _ in 0..1 + rand_below(rng, 8) {
                if len > 0 {
                    let i = rand_below(rng, len);
                    data[i] ^= 1 << (rng.next_u32() % 8);
                }
            }
        }
        1 => data.truncate(rand_below(rng, len + 1)),
        2 => {
            let at = rand_below(rng, len + 1);
            let n = 1 + rand_below(rng, 16);
            let bytes: Vec<u8> = (0..n).map(|_| rng.next_u32() as u8).collect();
            data.splice(at..at, bytes);
        }
        3 => {
            // Duplicate a chunk somewhere else.
            if len > 0 {
                let a = rand_below(rng, len);
                let n = 1 + rand_below(rng, (len - a).min(512));
                let chunk = data[a..a + n].to_vec();
                let at = rand_below(rng, len + 1);
                data.splice(at..at, chunk);
            }
        }
        4 => {
            // Replace a run of number characters with an odd number.
            if len > 0 {
                let start = rand_below(rng, len);
                if let Some(p) = data[start..].iter().position(|b| b.is_ascii_digit()) {
                    let a = start + p;
                    let e = data[a..].iter().position(|b| !(b.is_ascii_digit() || *b == b'.' || *b == b'e' || *b == b'-')).map_or(len, |q| a + q);
                    let num = NUMBERS[rand_below(rng, NUMBERS.len())].as_bytes().to_vec();
                    data.splice(a..e, num);
                }
            }
        }
        5 => {
            // Overwrite 4 bytes with an interesting u32 (counts, sizes, offsets).
            if len >= 4 {
                let v: u32 = [0, 1, 0x7fff_ffff, 0xffff_ffff, len as u32, (len as u32) / 50, 600 << 20][rand_below(rng, 7)];
                let at = if rng.next_u32() % 2 == 0 { 80.min(len - 4) } else { rand_below(rng, len - 3) };
                data[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
        6 => {
            if len > 0 {
                let a = rand_below(rng, len);
                let n = 1 + rand_below(rng, (len - a).min(256));
                data.drain(a..a + n);
            }
        }
        _ => {
            // Swap two lines (or chunks) of text.
            let lines: Vec<&[u8]> = data.split(|&b| b == b'\n').collect();
            if lines.len() > 2 {
                let (i, j) = (rand_below(rng, lines.len()), rand_below(rng, lines.len()));
                let mut l: Vec<Vec<u8>> = lines.iter().map(|x| x.to_vec()).collect();
                l.swap(i, j);
                *data = l.join(&b'\n');
            }
        }
    }
}

/// The most work any one input took: items counted, bytes allocated (each its own maximum).
#[derive(Default, Debug)]
struct Worst {
    items: u64,
    bytes: u64,
}

fn check(name: &str, seed: u64, input: &[u8], worst: &mut Worst) {
    let (w, result): (Work, _) = crate::work::measure(|| std::panic::catch_unwind(|| read_mesh(name, input, &Options::default())));
    if result.is_err() {
        let dump = std::env::temp_dir().join(format!("weft-fuzz-smoke-{name}-{seed}.bin"));
        let _ = std::fs::write(&dump, input);
        panic!("read_mesh panicked on {name} mutation seed {seed}; input saved to {}", dump.display());
    }
    let est = std::panic::catch_unwind(|| estimate(name, input));
    if est.is_err() {
        let dump = std::env::temp_dir().join(format!("weft-fuzz-smoke-{name}-{seed}.bin"));
        let _ = std::fs::write(&dump, input);
        panic!("estimate panicked on {name} mutation seed {seed}; input saved to {}", dump.display());
    }
    if let (Ok(im), Ok(est)) = (result.as_ref().unwrap(), est.unwrap()) {
        assert_eq!(est.triangles, im.report.triangles_read as u64, "{name} seed {seed}: estimate {est:?}");
        assert!(est.peak_bytes >= input.len() as u64);
    }
    if let Ok(im) = result.unwrap() {
        let n = im.mesh.vertices.len();
        assert!(im.mesh.triangles.iter().flatten().all(|&i| (i as usize) < n), "{name} seed {seed}: index out of range");
        assert!(im.mesh.vertices.iter().flatten().all(|c| c.is_finite()), "{name} seed {seed}: non-finite vertex");
        assert_eq!(im.report.triangles, im.mesh.triangles.len());
        // A solid slot's check on whatever the mutation left: closed (every edge used twice)
        // or refused in words, never a panic.
        let mut mesh = im.mesh.clone();
        let closed = std::panic::catch_unwind(move || weft::import::close::close_solid(name, &mut mesh).map(|c| (c, mesh)));
        match closed {
            Err(_) => panic!("close_solid panicked on {name} mutation seed {seed}"),
            Ok(Ok((c, mesh))) if c.nonmanifold_edges == 0 => {
                let mut edges: Vec<(u32, u32)> =
                    mesh.triangles.iter().flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])))).collect();
                edges.sort_unstable();
                let single = edges.chunk_by(|a, b| a == b).filter(|r| r.len() == 1).count();
                assert_eq!(single, 0, "{name} seed {seed}: closed, yet {single} edges are used once");
            }
            Ok(Ok(_)) => {}
            Ok(Err(e)) => assert!(e.to_string().contains("is not a closed solid"), "{e}"),
        }
    }
    worst.items = worst.items.max(w.items);
    worst.bytes = worst.bytes.max(w.bytes);
}

fn unzip(bytes: &[u8]) -> Vec<(String, Vec<u8>)> {
    let mut z = zip::ZipArchive::new(Cursor::new(bytes)).unwrap();
    (0..z.len())
        .map(|i| {
            let mut f = z.by_index(i).unwrap();
            let mut data = Vec::new();
            f.read_to_end(&mut data).unwrap();
            (f.name().unwrap().to_string(), data)
        })
        .collect()
}

fn rezip(entries: &[(String, Vec<u8>)]) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, body) in entries {
        w.start_file(name.as_str(), opts).unwrap();
        w.write_all(body).unwrap();
    }
    w.finish().unwrap().into_inner()
}

#[test]
fn mutated_fixtures_never_panic() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    // Files only (wireframes have their own folder and their own fuzzing, tests/freeform).
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.len() >= 8, "fixtures missing: {names:?}");
    let mut seeds: Vec<(String, Vec<u8>)> = names.iter().map(|n| (n.clone(), std::fs::read(dir.join(n)).unwrap())).collect();
    // Small hostile inputs made by the generators (never committed as files).
    use weft::testgen::mesh as gen;
    seeds.push(("gen-control.stl".into(), gen::ascii_stl_control_byte(24)));
    seeds.push(("gen.obj".into(), gen::obj(24)));
    seeds.push(("gen-siblings.3mf".into(), gen::three_mf_siblings(3)));
    seeds.push(("gen-nested.3mf".into(), gen::three_mf_nested(8)));
    seeds.push(("gen-too-deep.3mf".into(), gen::three_mf_nested(weft::import::MAX_XML_DEPTH + 1)));
    let mut worst = Worst::default();
    let mut runs = 0;
    for (k, (name, original)) in seeds.iter().enumerate() {
        let original = original.clone();
        // Fewer rounds for big files so the test stays fast in debug builds.
        // WEFT_FUZZ_ROUNDS=n multiplies the rounds for a longer local run.
        let scale: u64 = std::env::var("WEFT_FUZZ_ROUNDS").ok().and_then(|v| v.parse().ok()).unwrap_or(1);
        let rounds = scale * if original.len() > 20_000 { 150 } else { 2000 };
        let is_zip = name.ends_with(".3mf");
        let entries = if is_zip { unzip(&original) } else { Vec::new() };
        for r in 0..rounds {
            let seed = (k as u64) << 32 | r;
            let mut rng = Pcg64::seed_from_u64(seed);
            let input = if is_zip && r % 2 == 0 {
                // Mutate the XML parts, then zip them again so the parser sees the damage.
                let mut e = entries.clone();
                for _ in 0..1 + rng.next_u32() % 3 {
                    let i = rand_below(&mut rng, e.len());
                    mutate(&mut rng, &mut e[i].1);
                }
                rezip(&e)
            } else {
                let mut data = original.clone();
                for _ in 0..1 + rng.next_u32() % 3 {
                    mutate(&mut rng, &mut data);
                }
                data
            };
            check(name, seed, &input, &mut worst);
            runs += 1;
        }
    }
    // A few hand-written nasties.
    let nasty: &[&[u8]] = &[
        b"solid",
        b"solid\n",
        b"solid x\nfacet",
        b"solid x\nfacet normal",
        b"v",
        b"f",
        b"v 1 2 3\nf -1 -1 -1",
        b"v 1 2 3\nf 1/ /1 //",
        b"PK\x03\x04",
        b"PK\x03\x04\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00",
        b"\xEF\xBB\xBF",
        b"\xEF\xBB\xBFsolid a\nendsolid",
        &[0u8; 84],
        &[0xffu8; 84],
    ];
    for (i, n) in nasty.iter().enumerate() {
        check("nasty", i as u64, n, &mut worst);
    }
    // No input of a few kB makes the reader work or allocate as if it were huge (counted,
    // not timed: a forged count, a runaway loop or an expansion shows here on any machine).
    println!("{runs} mutated inputs, the most work of one: {worst:?}");
    assert!(worst.items < 10_000_000 && worst.bytes < 64 << 20, "an input of a few kB took {worst:?}");
}
