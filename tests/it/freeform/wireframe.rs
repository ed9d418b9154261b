//! Reading wireframe designs (issue 13): every real design of `tests/fixtures/wireframes/`
//! (copied byte for byte from `../shared/wireframes/`) reads with the counts its README states;
//! OBJ line elements and a CSV of beams read; every problem a design can have is listed with
//! its place; hostile files are refused in words.

use weft::freeform::wireframe::{read, Error, Format, Ground, Options};

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/wireframes").join(name)).unwrap()
}

fn problems(name: &str, text: &str) -> Vec<String> {
    match read(name, text.as_bytes(), &Options::default()) {
        Err(Error::Invalid { problems, .. }) => problems,
        other => panic!("{name}: {other:?}"),
    }
}

#[test]
fn every_real_design_reads_with_its_counts_and_grounded_joints() {
    // (file, joints, beams, grounded) as the README and the files state them.
    for (file, joints, beams, grounded) in [
        ("four-frame.json", 5, 4, 2),
        ("semi_sphere.json", 40, 87, 10),
        ("klein_bottle.json", 126, 246, 6),
        ("voronoi_S1_03-14-2019_w_layer.json", 162, 306, 14),
        ("topopt-310_S1_03-14-2019_w_layer.json", 160, 310, 39),
        ("duck.json", 305, 909, 72),
        ("cantilever_beam_truss.json", 817, 2197, 103),
    ] {
        let w = read(file, &fixture(file), &Options::default()).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!((w.joints.len(), w.beams.len(), w.grounded.iter().filter(|&&g| g).count()), (joints, beams, grounded), "{file}");
        assert!(w.grounded_by_file, "{file}: the file's own grounded joints");
        assert_eq!(w.format, if file.starts_with("cantilever") { Format::Conmech } else { Format::AssemblyInstances });
    }
    // conmech is in metres: its first node (−0.1, −0.05, −0.05) m is (−100, −50, −50) mm.
    let w = read("t.json", &fixture("cantilever_beam_truss.json"), &Options::default()).unwrap();
    assert!((w.joints[0] - weft::geom::DVec3::new(-100.0, -50.0, -50.0)).length() < 1e-9, "{:?}", w.joints[0]);
    // Grounding the lowest joints instead: four-frame's two feet are its lowest (z = −10).
    let low = read("four-frame.json", &fixture("four-frame.json"), &Options { ground: Ground::Lowest, ..Options::default() }).unwrap();
    assert_eq!(low.grounded.iter().filter(|&&g| g).count(), 2);
    assert!(!low.grounded_by_file);
}

#[test]
fn obj_lines_and_csv_beams_read_and_ground_their_lowest_joints() {
    let obj = "# a tripod\nv 0 0 0\nv 10 0 0\nv 5 8 0\nv 5 3 10\nl 1 4\nl 2 4 3\nl -2 -4\n";
    let w = read("tripod.obj", obj.as_bytes(), &Options::default()).unwrap();
    assert_eq!(w.beams[..3], [[0, 3], [1, 3], [3, 2]]);
    // `l -2 -4` counts back from the last vertex: the third and the first.
    assert_eq!(w.beams.len(), 4);
    assert_eq!(w.beams[3], [2, 0]);
    assert_eq!(w.grounded, vec![true, true, true, false]);
    let csv = "x1,y1,z1,x2,y2,z2\n0,0,0, 0,0,10\n0,0,10.0004, 10,0,10\n10,0,0;10,0,10\n";
    let w = read("frame.csv", csv.as_bytes(), &Options::default()).unwrap();
    assert_eq!(w.joints.len(), 4, "the ends 0.4 µm apart are one joint: {:?}", w.joints);
    assert_eq!(w.beams, vec![[0, 1], [1, 2], [3, 2]]);
    assert_eq!(w.grounded, vec![true, false, false, true]);
}

#[test]
fn every_problem_is_listed_with_its_place() {
    // OBJ: a zero-length beam, a repeat, a missing vertex, a non-finite vertex, a floating part.
    let obj = "v 0 0 0\nv 0 0 10\nv 0 0 10\nv 20 0 5\nv 30 0 5\nv nan 1 1\nl 1 2\nl 2 3\nl 2 1\nl 1 9\nl 4 5\nl 5 6\n";
    let p = problems("bad.obj", obj).join("\n");
    for want in [
        "line 10 names vertex 9, which the file does not have",
        "vertex 6 (line 6) is at (NaN, 1, 1): coordinates must be finite",
        "line 8 has length 0.0000 mm",
        "line 9 repeats line 7",
        "2 beam(s) starting with line 11 are not connected to any grounded joint",
    ] {
        assert!(p.contains(want), "missing \"{want}\" in:\n{p}");
    }
    // JSON: a beam to a node that does not exist; no grounded joint when the file marks one
    // but it carries no beam and the lowest rule is not asked for… is grounded by the lowest.
    let ai = r#"{"unit": "millimeter", "node_list": [
        {"point": {"X": 0, "Y": 0, "Z": 0}, "node_id": 0, "is_grounded": 1},
        {"point": {"X": 0, "Y": 0, "Z": 5}, "node_id": 1, "is_grounded": 0}],
        "element_list": [{"end_node_ids": [0, 1], "element_id": 0}, {"end_node_ids": [1, 7], "element_id": 1}]}"#;
    let p = problems("ai.json", ai).join("\n");
    assert!(p.contains("element 1 names node 7, which the file does not have"), "{p}");
    // The listing stops at 12 and counts the rest.
    let mut many = String::from("v 0 0 0\nv 0 0 1\nl 1 2\n");
    for _ in 0..20 {
        many.push_str("l 1 2\n");
    }
    let p = problems("many.obj", &many);
    assert_eq!(p.len(), 13);
    assert_eq!(p[12], "and 8 more problem(s)");
}

#[test]
fn hostile_files_are_refused_in_words() {
    let e = read("x.json", b"{\"node_list\": [", &Options::default()).unwrap_err().to_string();
    assert!(e.contains("x.json, line 1, column") && e.contains("not JSON"), "{e}");
    let e = read("x.json", b"{\"points\": []}", &Options::default()).unwrap_err().to_string();
    assert!(e.contains("neither an assembly_instances design"), "{e}");
    let e = read("x.json", br#"{"unit": "furlong", "node_list": [], "element_list": []}"#, &Options::default()).unwrap_err().to_string();
    assert!(e.contains("unit \"furlong\""), "{e}");
    let e = read("x.obj", b"v 0 0 0\nv 1 0 0\n", &Options::default()).unwrap_err().to_string();
    assert!(e.contains("no line elements") && e.contains("no faces"), "{e}");
    // Faces without line elements are a mesh whose edges are the beams, said so.
    let w = read("x.obj", b"v 0 0 0\nv 1 0 0\nf 1 2 1\n", &Options::default()).unwrap();
    assert_eq!(w.beams.len(), 1);
    assert!(w.notes[0].contains("read 1 faces as 1 beams"), "{:?}", w.notes);
    // A face of more corners than a design has beams is refused as it is read.
    let corners = 3 * weft::freeform::wireframe::MAX_BEAMS + 1;
    let huge = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nf {}\n", "1 2 3 ".repeat(corners / 3 + 1));
    let e = read("huge.obj", huge.as_bytes(), &Options::default()).unwrap_err().to_string();
    assert!(e.contains("line 4") && e.contains("plan the design in parts"), "{e}");
    let e = read("x.csv", b"1,2,3,4,5\n", &Options::default()).unwrap_err().to_string();
    assert!(e.contains("line 1") && e.contains("5 numbers"), "{e}");
    let e = read("x.obj", &[0xff, 0xfe, 0x00], &Options::default()).unwrap_err().to_string();
    assert!(e.contains("not text"), "{e}");
    let big = vec![b' '; weft::freeform::wireframe::MAX_BYTES + 1];
    assert!(matches!(read("big.json", &big, &Options::default()), Err(Error::TooBig { .. })));
    // No grounded joint possible: every joint NaN-high is not finite, so none is lowest.
    let p = problems("nan.obj", "v 0 0 nan\nv 0 0 nan\nl 1 2\n").join("\n");
    assert!(p.contains("no joint is grounded"), "{p}");
}

/// Mutated wireframes (bytes flipped, inserted, deleted, in the real designs and in small OBJ
/// and CSV ones) never panic the reader, and whatever it accepts plans or is refused without
/// a panic.
#[test]
fn mutated_wireframes_never_panic() {
    use rand_core::{Rng, SeedableRng};
    use rand_pcg::Pcg64;
    use weft::freeform::{plan, precedence};
    let mut seeds: Vec<(String, Vec<u8>)> = vec![
        ("small.obj".into(), b"v 0 0 0\nv 10 0 0\nv 0 10 0\nv 0 0 10\nl 1 4\nl 2 4\nl 3 4\nl 1 2 3\n".to_vec()),
        ("small.csv".into(), b"x1,y1,z1,x2,y2,z2\n0,0,0,0,0,5\n0,0,5,5,0,5\n5,0,5,5,0,0\n".to_vec()),
    ];
    for f in ["four-frame.json", "semi_sphere.json"] {
        seeds.push((f.into(), fixture(f)));
    }
    let nozzle = precedence::Options { nozzle: precedence::Nozzle::default(), beam_radius_mm: 0.5, directionality: true, collision: true, tilt_deg: 0.0 };
    let mut accepted = 0;
    for (k, (name, original)) in seeds.iter().enumerate() {
        for r in 0..300u64 {
            let mut rng = Pcg64::seed_from_u64((k as u64) << 32 | r);
            let mut data = original.clone();
            for _ in 0..1 + rng.next_u32() % 3 {
                let at = (rng.next_u32() as usize) % data.len().max(1);
                match rng.next_u32() % 3 {
                    0 if !data.is_empty() => data[at] = b"0123456789-.,e{}[]\"ln \n"[(rng.next_u32() % 20) as usize],
                    1 => data.insert(at.min(data.len()), b"9e300"[(rng.next_u32() % 5) as usize]),
                    _ if !data.is_empty() => {
                        data.remove(at);
                    }
                    _ => {}
                }
            }
            let read = std::panic::catch_unwind(|| read(name, &data, &Options::default()));
            let Ok(Ok(w)) = read else {
                assert!(read.is_ok(), "{name} round {r}: the reader panicked");
                continue;
            };
            accepted += 1;
            let planned = std::panic::catch_unwind(|| {
                let c = precedence::constraints(&w.joints, &w.beams, &nozzle, &mut |_| {}).unwrap();
                let a = plan::Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: &c };
                let _ = plan::plan(
                    &a,
                    &plan::Options {
                        mode: plan::Mode::Strict,
                        cost: plan::Cost::Exact,
                        connection: true,
                        section: weft::freeform::frame::Section { diameter_mm: 1.0, e_mpa: 2600.0, g_mpa: 1100.0 },
                        load_n: 1e-4,
                        budget_s: 1.0,
                    },
                    &mut |_, _| {},
                );
            });
            assert!(planned.is_ok(), "{name} round {r}: planning a mutated design panicked");
        }
    }
    assert!(accepted > 100, "only {accepted} mutated designs were read: the mutations are too harsh to reach the planner");
}

#[test]
fn a_design_far_over_the_beam_limit_is_refused_before_it_is_parsed() {
    // 600 000 beams of CSV: refused by counting its lines, naming the count.
    let mut text = String::from("x1,y1,z1,x2,y2,z2\n");
    for i in 0..600_000 {
        text.push_str(&format!("{},{},0,{},{},5\n", i % 700, i / 700, i % 700, i / 700));
    }
    let e = weft::freeform::wireframe::read("huge.csv", text.as_bytes(), &weft::freeform::wireframe::Options::default()).unwrap_err().to_string();
    assert!(e.contains("600000 beams is more than 200000"), "{e}");
    let obj = format!("v 0 0 0\nv 0 0 1\n{}", "l 1 2\n".repeat(200_001));
    let e = weft::freeform::wireframe::read("huge.obj", obj.as_bytes(), &weft::freeform::wireframe::Options::default()).unwrap_err().to_string();
    assert!(e.contains("200001 beams"), "{e}");
}
