//! Large and hostile inputs for `weft::import` (issue 7: no input hangs, exhausts or escapes).
//!
//! - Growth: for every parser, the work at k·n (bytes read, hash probes, allocations, bytes
//!   allocated, peak heap: `crate::work`) over the work at n stays within linear growth. No
//!   times: the same verdict on any machine under any load. The 3MF reader that found each
//!   element's line by counting from the start of the part was quadratic (≈ 64 at k = 8).
//! - Limits: nesting, forged and multiplied counts are refused with the number, the limit and
//!   the fix, before the memory is allocated (resident memory checked where Linux lets us).
//! - The estimate is exact in triangles and an upper bound of the measured memory peak.
//!
//! Tests here run one at a time (`LOCK`) so resident-memory readings do not mix.
//! `cargo test --release --test it import_hostile:: -- --nocapture` prints the measurements;
//! `-- --ignored --nocapture memory_per_triangle` prints the per-triangle peaks at 2 M triangles.

use crate::work::work;
use std::io::{Cursor, Write};
use std::sync::Mutex;
use weft::import::{estimate, read_mesh, Error, Format, Options, MAX_IMPORT_BYTES, MAX_TRIANGLES, MAX_XML_DEPTH};
use weft::testgen::mesh as gen;

static LOCK: Mutex<()> = Mutex::new(());

fn lock() -> std::sync::MutexGuard<'static, ()> {
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// Counts the work of reading `make(n)` and `make(k·n)` (XML bytes read, hash-table probes,
/// allocations, bytes allocated, peak heap: [`crate::work`], the same on any machine) and
/// asserts linear growth against k_eff, the ratio of the triangles actually made. The 3MF
/// reader that found each element's line by counting from the start of the part was
/// quadratic (64× at k = 8) and fails this.
fn assert_linear(what: &str, make: fn(usize) -> Vec<u8>, name: &str, n: usize, k: usize) {
    let (small, big) = (make(n), make(k * n));
    let tris = |b: &[u8]| estimate(name, b).unwrap().triangles as f64;
    let k_eff = tris(&big) / tris(&small);
    let read = |bytes: &[u8]| {
        let r = read_mesh(name, bytes, &Options::default());
        assert!(r.is_ok(), "{name}: {}", r.err().map(|e| e.to_string()).unwrap_or_default());
        std::hint::black_box(r.ok());
    };
    println!("{what}: {:.0} → {:.0} triangles ({} → {} bytes)", tris(&small), tris(&big), small.len(), big.len());
    crate::work::assert_linear(what, k_eff, work(|| read(&small)), work(|| read(&big)));
}

#[test]
fn binary_stl_reads_in_linear_time() {
    let _g = lock();
    assert_linear("binary STL", gen::binary_stl_sphere, "a.stl", 10_000, 8);
}

#[test]
fn ascii_stl_reads_in_linear_time() {
    let _g = lock();
    assert_linear("ASCII STL", gen::ascii_stl, "a.stl", 5_000, 8);
}

#[test]
fn obj_reads_in_linear_time() {
    let _g = lock();
    assert_linear("OBJ", gen::obj, "a.obj", 5_000, 8);
}

#[test]
fn three_mf_reads_in_linear_time() {
    let _g = lock();
    assert_linear("3MF", gen::three_mf, "a.3mf", 1_000, 8);
}

#[test]
fn three_mf_sibling_objects_read_in_linear_time() {
    let _g = lock();
    assert_linear("3MF siblings", gen::three_mf_siblings, "a.3mf", 250, 8);
}

#[test]
fn three_mf_estimate_counts_in_linear_time() {
    let _g = lock();
    // The estimate's counting pass over the XML (no numbers parsed, nothing stored per element).
    let (small, big) = (gen::three_mf(60_000), gen::three_mf(480_000));
    let k = estimate("a.3mf", &big).unwrap().triangles as f64 / estimate("a.3mf", &small).unwrap().triangles as f64;
    let count = |b: &[u8]| work(|| _ = std::hint::black_box(estimate("a.3mf", b).unwrap()));
    crate::work::assert_linear("3MF estimate", k, count(&small), count(&big));
}

// ---------- nesting, forged and multiplied counts ----------

#[test]
fn deep_xml_nesting_is_refused_at_the_limit() {
    let _g = lock();
    // Within the limit: read.
    let im = read_mesh("n.3mf", &gen::three_mf_nested(MAX_XML_DEPTH - 4), &Options::default()).unwrap();
    assert_eq!(im.report.triangles, 1);
    // Far past it: a clean error naming the limit and the line, after ~64 elements of work.
    for n in [MAX_XML_DEPTH, 100_000, 1_000_000] {
        let e = read_mesh("n.3mf", &gen::three_mf_nested(n), &Options::default()).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, Error::Malformed { .. }), "{msg}");
        assert!(msg.contains(&format!("deeper than {MAX_XML_DEPTH} levels")) && msg.contains("3D/3dmodel.model line "), "{msg}");
    }
}

/// Resident-memory high-water mark while `f` runs, over the resident memory before, when
/// Linux lets us reset the mark (`/proc/self/clear_refs`); `None` elsewhere.
fn peak_rss_during<T>(f: impl FnOnce() -> T) -> (T, Option<u64>) {
    let field = |name: &str| -> Option<u64> {
        let s = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = s.lines().find(|l| l.starts_with(name))?;
        let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb * 1024)
    };
    let reset = std::fs::write("/proc/self/clear_refs", "5").is_ok();
    let before = field("VmRSS:");
    let out = f();
    let after = field("VmHWM:");
    match (reset, before, after) {
        (true, Some(b), Some(a)) => (out, Some(a.saturating_sub(b))),
        _ => (out, None),
    }
}

/// Refused with `TooLarge`, naming `count` and the limit, and (where measurable) with under
/// `max_rss` bytes of memory touched.
fn assert_refused(name: &str, bytes: &[u8], count: &str, max_rss: u64) {
    let (r, rss) = peak_rss_during(|| read_mesh(name, bytes, &Options::default()));
    let e = r.err().unwrap_or_else(|| panic!("{name}: read"));
    let msg = e.to_string();
    println!("{name}: {msg} (resident peak +{} KiB)", rss.unwrap_or(0) >> 10);
    assert!(matches!(e, Error::TooLarge { .. }), "{msg}");
    assert!(msg.contains(count), "{msg} should name {count}");
    let limit = group(MAX_TRIANGLES as u64);
    assert!(msg.contains(&limit) && msg.contains("decimate"), "{msg}");
    if let Some(rss) = rss {
        assert!(rss < max_rss, "{name}: {} MiB touched before refusing", rss >> 20);
    }
    // The estimate agrees, without reading.
    let est = estimate(name, bytes).unwrap();
    assert!(est.triangles > MAX_TRIANGLES as u64 && est.check(name).is_err(), "{est:?}");
}

fn group(n: u64) -> String {
    let d = n.to_string();
    let mut out = String::new();
    for (i, c) in d.chars().enumerate() {
        if i > 0 && (d.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[test]
fn forged_binary_stl_count_is_refused_before_allocating() {
    let _g = lock();
    // A header promising MAX + 1 triangles in a file of exactly that length: zeroed pages the
    // reader must never touch (the allocation is lazy, so the test itself costs nothing).
    let n = MAX_TRIANGLES + 1;
    let mut bytes = vec![0u8; 84 + 50 * n];
    bytes[80..84].copy_from_slice(&(n as u32).to_le_bytes());
    assert_refused("forged.stl", &bytes, &group(n as u64), 16 << 20);

    // A count far past the bytes present (over 1000× the file): not an STL at all, and
    // nothing is allocated.
    let mut short = vec![0u8; 84 + 50 * 10];
    short[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = read_mesh("short.stl", &short, &Options::default()).unwrap_err().to_string();
    assert!(e.starts_with("short.stl is not an STL file: its size does not fit the triangle count"), "{e}");
    assert_eq!(estimate("short.stl", &short).unwrap().triangles, 10);
}

#[test]
fn too_many_obj_and_ascii_stl_triangles_are_refused_before_allocating() {
    let _g = lock();
    // One polygon with MAX + 3 corners: MAX + 1 fan triangles from 10 MB of text.
    let mut obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf".to_vec();
    for _ in 0..(MAX_TRIANGLES + 2).div_ceil(3) + 1 {
        obj.extend_from_slice(b" 1 2 3");
    }
    obj.push(b'\n');
    let tris = ((MAX_TRIANGLES + 2).div_ceil(3) + 1) * 3 - 2;
    assert_refused("fan.obj", &obj, &group(tris as u64), 16 << 20);

    let mut stl = b"solid fan\nfacet normal 0 0 0\nouter loop\n".to_vec();
    for _ in 0..MAX_TRIANGLES + 3 {
        stl.extend_from_slice(b"vertex 0 0 0\n");
    }
    stl.extend_from_slice(b"endloop\nendfacet\nendsolid fan\n");
    assert_refused("fan.stl", &stl, &group(MAX_TRIANGLES as u64 + 1), 16 << 20);
}

fn package(model: &[u8]) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    w.start_file("3D/3dmodel.model", opts).unwrap();
    w.write_all(model).unwrap();
    w.finish().unwrap().into_inner()
}

const HEAD: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<model unit="millimeter" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">
<resources>
"#;

/// An object of `t` triangles (a strip) as 3MF XML.
fn strip_object(id: u32, t: usize) -> String {
    let mut s = format!("<object id=\"{id}\" type=\"model\"><mesh><vertices>\n");
    for i in 0..t + 2 {
        s.push_str(&format!("<vertex x=\"{}\" y=\"{}\" z=\"0\"/>\n", i / 2, i % 2));
    }
    s.push_str("</vertices><triangles>\n");
    for i in 0..t {
        s.push_str(&format!("<triangle v1=\"{i}\" v2=\"{}\" v3=\"{}\"/>\n", i + 1, i + 2));
    }
    s.push_str("</triangles></mesh></object>\n");
    s
}

#[test]
fn multiplied_3mf_build_is_refused_before_placing() {
    let _g = lock();
    // 1,000 triangles placed 5,001 times: 5,001,000 triangles from a 40 KB file.
    let mut m = String::from(HEAD);
    m.push_str(&strip_object(1, 1000));
    m.push_str("<object id=\"2\"><components>\n");
    for i in 0..5001 {
        m.push_str(&format!("<component objectid=\"1\" transform=\"1 0 0 0 1 0 0 0 1 0 0 {i}\"/>\n"));
    }
    m.push_str("</components></object>\n</resources>\n<build><item objectid=\"2\"/></build>\n</model>\n");
    let bytes = package(m.as_bytes());
    assert_refused("copies.3mf", &bytes, "5,001,000 triangles", 32 << 20);
}

#[test]
fn three_mf_triangles_are_counted_as_they_stream() {
    let _g = lock();
    // MAX + 1 triangle elements (200 MB of XML, deflated to a few hundred KB, streamed into
    // the zip writer): refused when the count passes the limit, at that element's line.
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    w.start_file("3D/3dmodel.model", opts).unwrap();
    w.write_all(HEAD.as_bytes()).unwrap();
    w.write_all(b"<object id=\"1\"><mesh><vertices><vertex x=\"0\" y=\"0\" z=\"0\"/><vertex x=\"1\" y=\"0\" z=\"0\"/><vertex x=\"0\" y=\"1\" z=\"0\"/></vertices><triangles>\n").unwrap();
    let line = b"<triangle v1=\"0\" v2=\"1\" v3=\"2\"/>\n".repeat(10_000);
    for _ in 0..=MAX_TRIANGLES / 10_000 {
        w.write_all(&line).unwrap();
    }
    w.write_all(b"</triangles></mesh></object></resources><build><item objectid=\"1\"/></build></model>\n").unwrap();
    let bytes = w.finish().unwrap().into_inner();
    let e = read_mesh("stream.3mf", &bytes, &Options::default()).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::TooLarge { .. }), "{msg}");
    let at = format!("3D/3dmodel.model line {}", 4 + MAX_TRIANGLES + 1);
    assert!(msg.contains(&at) && msg.contains(&format!("more than {} triangles", group(MAX_TRIANGLES as u64))), "{msg}");
    assert!(msg.contains("decimate"), "{msg}");
}

#[test]
fn too_many_zip_entries_are_refused() {
    let _g = lock();
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for i in 0..10_001 {
        w.start_file(format!("{i}"), opts).unwrap();
    }
    let bytes = w.finish().unwrap().into_inner();
    let e = read_mesh("many.3mf", &bytes, &Options::default()).unwrap_err().to_string();
    assert!(e.contains("10,001 parts") && e.contains("10,000"), "{e}");
}

// ---------- STL binary or ASCII ----------

#[test]
fn ascii_stl_with_a_control_byte_reads_as_ascii() {
    let _g = lock();
    let plain = read_mesh("a.stl", &gen::ascii_stl(2000), &Options::default()).unwrap();
    for name in ["a.stl", "a.bin"] {
        let im = read_mesh(name, &gen::ascii_stl_control_byte(2000), &Options::default()).unwrap();
        assert_eq!(im.report.format, Some(Format::StlAscii));
        assert_eq!(im.mesh, plain.mesh);
    }
}

#[test]
fn stl_that_is_neither_says_which_rule_failed() {
    let _g = lock();
    // Starts with "solid", holds NULs, and its length disagrees with the header count.
    let mut b = gen::binary_stl_sphere(100);
    b.truncate(b.len() - 20);
    let e = read_mesh("cut.stl", &b, &Options::default()).unwrap_err().to_string();
    assert!(
        e.starts_with("cut.stl: triangle 120 (byte 6034): the file ends after 6,064 bytes but its header says it holds 120 triangles (6,084 bytes)"),
        "{e}"
    );
    assert!(e.ends_with("the file was cut short; export it again"), "{e}");
    // Without the .stl name it is unknown, both rules named.
    let e = read_mesh("cut.bin", &b, &Options::default()).unwrap_err().to_string();
    assert!(e.contains("its size does not fit the triangle count a binary STL states at byte 80") && e.contains("is not text (byte "), "{e}");
    // A file named .stl that is random bytes is not an STL file, and says why in one clause.
    let junk: Vec<u8> = (0..300u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8).collect();
    assert_eq!(
        read_mesh("r.stl", &junk, &Options::default()).unwrap_err().to_string(),
        "r.stl is not an STL file: its size does not fit the triangle count a binary STL states at byte 80, and it does not start with the word \"solid\" as a text STL does; export the mesh again as STL, OBJ or 3MF"
    );
    assert_eq!(
        read_mesh("notes.stl", b"shopping list: milk, eggs\n", &Options::default()).unwrap_err().to_string(),
        "notes.stl is not an STL file: it is text, but not a text STL: that starts with the word \"solid\"; export the mesh again as STL, OBJ or 3MF"
    );
    // Text starting with "solid" but full of control bytes.
    let mut t = b"solid x\n".to_vec();
    t.extend((1u8..=20).cycle().take(200));
    let e = read_mesh("ctl.stl", &t, &Options::default()).unwrap_err().to_string();
    assert!(e.contains("control bytes (the first at byte 8)"), "{e}");
    // Binary text that does not start with "solid".
    let e = read_mesh("x.stl", b"hello, this is not a mesh but it is long enough to have a header of eighty-four bytes!!", &Options::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a text STL: that starts with the word \"solid\""), "{e}");
}

// ---------- strings from files ----------

fn zipped(model: &str) -> Vec<u8> {
    package(model.as_bytes())
}

#[test]
fn strings_from_files_are_bounded_in_messages() {
    let _g = lock();
    let huge = format!("mm{}\u{7}\u{1b}[31m", "x".repeat(1 << 20));
    let cases: Vec<(&str, Vec<u8>)> = vec![
        // A 1 MB unit with control characters.
        ("unit.3mf", zipped(&format!("{HEAD}</resources></model>").replace("millimeter", &huge))),
        // A 1 MB element name in a mismatched end tag.
        ("tag.3mf", zipped(&format!("{HEAD}<{}\u{1}></other></resources></model>", "a".repeat(1 << 20)))),
        // A long p:path.
        (
            "path.3mf",
            zipped(&format!(
                "{HEAD}<object id=\"1\"><components><component objectid=\"1\" p:path=\"/{}\u{2}\"/></components></object></resources></model>",
                "p".repeat(5000)
            )),
        ),
        // A 1 MB number in OBJ, and a token with an escape sequence in ASCII STL.
        ("num.obj", format!("v 0 0 {}\u{1b}\n", "9".repeat(1 << 20)).into_bytes()),
        ("tok.stl", format!("solid a\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\u{1b}[2J{}\n", "z".repeat(1 << 20)).into_bytes()),
    ];
    for (name, bytes) in cases {
        let e = read_mesh(name, &bytes, &Options::default()).unwrap_err().to_string();
        println!("{name}: {e}");
        assert!(e.len() < 600, "{name}: {} bytes of message", e.len());
        assert!(!e.chars().any(|c| c.is_control()), "{name}: control characters in {e:?}");
    }
}

// ---------- entities ----------

#[test]
fn entities_are_never_expanded() {
    let _g = lock();
    let mut dtd = String::from("<!DOCTYPE model [\n<!ENTITY lol \"lol\">\n");
    for i in 1..10 {
        dtd.push_str(&format!("<!ENTITY lol{i} \"{}\">\n", format!("&lol{};", if i == 1 { String::new() } else { (i - 1).to_string() }).repeat(10)));
    }
    dtd.push_str("<!ENTITY xxe SYSTEM \"file:///etc/passwd\">\n]>\n");
    for value in ["&lol9;", "&xxe;"] {
        let m = format!(
            "<?xml version=\"1.0\"?>\n{dtd}<model unit=\"millimeter\"><resources><object id=\"1\"><mesh><vertices>\
             <vertex x=\"{value}\" y=\"0\" z=\"0\"/></vertices></mesh></object></resources></model>"
        );
        let zip = zipped(&m);
        let (w, e) = crate::work::measure(|| read_mesh("lol.3mf", &zip, &Options::default()).unwrap_err().to_string());
        assert!(e.contains(&format!("x=\"{value}\" is not a finite number")), "{e}");
        // Not expanded: 10⁹ laughs would allocate gigabytes; reading this file takes a few MB.
        assert!(w.bytes < (16 << 20), "expanded? {w:?}");
    }
}

// ---------- estimate ----------

/// Binary STL of `n` separate triangles: no two corners meet, so nothing welds (the
/// cleaner's worst case for memory).
fn binary_stl_soup(n: usize) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&(n as u32).to_le_bytes());
    for i in 0..n {
        let (x, y) = ((i % 1000) as f32 * 3.0, (i / 1000) as f32 * 3.0);
        b.extend_from_slice(&[0u8; 12]);
        for p in [[x, y, 0.0], [x + 1.0, y, 0.0], [x, y + 1.0, 0.5]] {
            for c in p {
                b.extend_from_slice(&f32::to_le_bytes(c));
            }
        }
        b.extend_from_slice(&[0, 0]);
    }
    b
}

type Make = fn(usize) -> Vec<u8>;
const FORMATS: [(&str, Make, &str); 6] = [
    ("binary STL", gen::binary_stl_sphere, "a.stl"),
    ("binary STL soup", binary_stl_soup, "a.stl"),
    ("ASCII STL", gen::ascii_stl, "a.stl"),
    ("OBJ", gen::obj, "a.obj"),
    ("3MF", gen::three_mf, "a.3mf"),
    ("3MF siblings", gen::three_mf_siblings, "a.3mf"),
];

/// The resident-memory high-water mark of `read_mesh` on the file at `path`, over the
/// resident memory before it (the input, read; the thread pool started), measured in a child process: a fresh heap,
/// and glibc told to map every block of 64 KiB or more on its own and unmap it when freed,
/// so resident memory follows the live heap. `None` where Linux does not let us measure.
fn measured_peak(path: &std::path::Path) -> Option<u64> {
    let out = std::process::Command::new(std::env::current_exe().ok()?)
        .args(["import_hostile::child_peak_probe", "--exact", "--ignored", "--nocapture", "--test-threads=1"])
        .env("WEFT_PROBE_FILE", path)
        .env("MALLOC_MMAP_THRESHOLD_", "65536")
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().find_map(|l| l.split("WEFT_PEAK ").nth(1))?;
    line.split_whitespace().next()?.parse().ok()
}

/// The child of [`measured_peak`].
#[test]
#[ignore = "run by measured_peak in a child process"]
fn child_peak_probe() {
    let Some(path) = std::env::var_os("WEFT_PROBE_FILE") else { return };
    let path = std::path::PathBuf::from(path);
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let bytes = std::fs::read(&path).unwrap();
    // The process's one-time set-up is not the import's: the thread pool's threads, their
    // stacks and allocator arenas start on a small mesh first (else they add about 100 KiB
    // of resident memory, more under load, to whichever import comes first).
    std::hint::black_box(read_mesh("warm-up.stl", &gen::binary_stl_sphere(2_000), &Options::default()).unwrap());
    let (im, rss) = peak_rss_during(|| read_mesh(&name, &bytes, &Options::default()).unwrap());
    std::hint::black_box(&im);
    if let Some(rss) = rss {
        println!("\nWEFT_PEAK {rss}");
    }
}

/// For each format at about `n` triangles: the estimate's triangle count is exact and its
/// peak is at least the measured one. Returns (format, triangles, input bytes, estimated
/// and measured peak beyond the input).
fn estimate_vs_measured(n: usize) -> Vec<(&'static str, u64, u64, u64, Option<u64>)> {
    let dir = std::env::temp_dir().join(format!("weft-import-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut rows = Vec::new();
    for (what, make, name) in FORMATS {
        let n = if what == "3MF siblings" { n / 4 } else { n };
        let bytes = make(n);
        let est = estimate(name, &bytes).unwrap();
        let im = read_mesh(name, &bytes, &Options::default()).unwrap();
        assert_eq!(est.triangles, im.report.triangles_read as u64, "{what}");
        drop(im);
        let path = dir.join(name);
        std::fs::write(&path, &bytes).unwrap();
        let rss = measured_peak(&path);
        let input = bytes.len() as u64;
        let beyond = est.peak_bytes - input;
        if let Some(rss) = rss {
            assert!(beyond >= rss, "{what}: estimated {} KiB beyond the input, measured {} KiB", beyond >> 10, rss >> 10);
        }
        rows.push((what, est.triangles, input, beyond, rss));
    }
    let _ = std::fs::remove_dir_all(&dir);
    rows
}

fn print_rows(rows: &[(&str, u64, u64, u64, Option<u64>)]) {
    for (what, t, input, est, rss) in rows {
        let per = |b: u64| b as f64 / *t as f64;
        println!(
            "{what}: {t} triangles, input {:.0} B/tri, estimated peak {:.0} B/tri beyond the input, measured {}",
            per(*input),
            per(*est),
            rss.map_or("n/a".into(), |r| format!("{:.0} B/tri ({} MiB)", per(r), r >> 20))
        );
    }
}

#[test]
fn estimate_is_exact_in_triangles_and_bounds_the_peak() {
    let _g = lock();
    print_rows(&estimate_vs_measured(200_000));
}

/// `cargo test --release --test it import_hostile:: -- --ignored --nocapture memory_per_triangle`
/// (the measurement behind `MAX_TRIANGLES`).
#[test]
#[ignore = "measurement; 2 M triangles per format"]
fn memory_per_triangle() {
    let _g = lock();
    print_rows(&estimate_vs_measured(2_000_000));
}

#[test]
fn limits_are_consistent() {
    // A closed binary STL at the triangle limit fits the memory limit (so the triangle
    // limit, not an opaque byte count, is what users meet).
    let n = MAX_TRIANGLES as u64;
    let mut bytes = vec![0u8; 84 + 50 * MAX_TRIANGLES]; // lazily zeroed: never touched
    bytes[80..84].copy_from_slice(&(MAX_TRIANGLES as u32).to_le_bytes());
    let est = estimate("max.stl", &bytes).unwrap();
    assert_eq!(est.triangles, n);
    println!("binary STL at the limit: estimated peak {} MiB", est.peak_bytes >> 20);
    assert!(est.peak_bytes <= MAX_IMPORT_BYTES, "{} MiB", est.peak_bytes >> 20);
    assert!(est.check("max.stl").is_ok());
}
