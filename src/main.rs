//! `weft` — the command-line front end of the weft core.

use clap::{Parser, Subcommand};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use weft::catalog::share;
use weft::design::Design;
use weft::kinds::Registry;
use weft::pipeline::{self, Files, RunOptions};

mod send;

#[derive(Parser)]
#[command(
    name = "weft",
    version,
    about = "Slicer for architected lattices and research toolpaths (the CLI of the weft web app)",
    after_help = "Examples:
  weft new > cube.json                               write a default design (20 mm cube)
  weft run cube.json --out cube.gcode                slice it
  weft run cube.json --input part.stl --out part.gcode --report part.json
  weft run dome.json --input surface=dome.stl        fill a named input slot (weft jobs lists them)
  weft run cube.json --out dense.gcode --set job.slice.infill_density=0.5 --set name=dense
  weft run big.json --input part.stl --dry-run        state the work and check the budgets first
  weft analyze part.gcode --json                     measure any slicer's G-code
  weft share cube.json                               print a share-link fragment
  weft send part.gcode --to octoprint --url http://192.168.1.20:5000   upload it (key: --key or $WEFT_HOST_KEY)
  weft run cube.json --send-to moonraker --send-url http://pi:7125 --send-start   slice, upload, print
  weft bench                                         run the benchmarks of BENCHMARKS.md"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a design and write its G-code.
    Run {
        /// The design (JSON), or a share link / fragment (`#d=…`).
        design: String,
        /// Output file, or a folder to write <design name>.gcode in (.bgcode when the printer
        /// asks for binary G-code; .nc for the pneumatic flavour, .csv for poses); a name ending
        /// in .bgcode writes binary G-code, in .gcode text. Default: that file in the current
        /// folder. The name is made safe (no folders, no hidden or device names), since a design
        /// may come from anyone.
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Also write the run report (JSON) here (a folder: <design name>.report.json in it).
        #[arg(long)]
        report: Option<PathBuf>,
        /// An input file for a slot of the job: SLOT=FILE (e.g. surface=dome.stl), or FILE for
        /// the job's first slot (repeatable). `weft jobs` lists each job kind's slots.
        #[arg(long, value_name = "[SLOT=]FILE")]
        input: Vec<String>,
        /// Override a design field: PATH=VALUE (repeatable), e.g. job.slice.layer_height_mm=0.1.
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Use a printer profile (replaces the design's printer section, before any --set):
        /// generic-220, prusa-mk3, prusa-mk4, prusa-mini, prusa-xl, klipper-220, ender-3, five-axis-head, bioprinter-pneumatic.
        #[arg(long, value_name = "ID")]
        printer: Option<String>,
        /// Threads to compute on (default: every core). 1 computes on one thread, as the
        /// browser's worker does on a page without cross-origin isolation; the G-code is the
        /// same bytes at any count.
        #[arg(long, value_name = "N")]
        threads: Option<usize>,
        /// Write the G-code a job sends ahead while it runs here, as soon as it is sent: a
        /// freeform plan's first beams, which a printer can start on while planning goes on
        /// (the final file's moves begin with them). A folder: <design name>.ahead.gcode in it.
        #[arg(long, value_name = "FILE")]
        ahead: Option<PathBuf>,
        /// No progress on stderr.
        #[arg(long, short)]
        quiet: bool,
        /// Only state the run's work (each stage's estimate: counts, memory, time) and whether
        /// it is within the budgets; write nothing but the --report (the plan as JSON).
        #[arg(long)]
        dry_run: bool,
        /// Send the written G-code to a print host (see `weft send`).
        #[command(flatten)]
        send: SendOptions,
    },
    /// Send a G-code file to a print host (Moonraker/Klipper or OctoPrint) and say its job state.
    Send {
        /// The G-code file (sent under its own name, byte for byte).
        file: PathBuf,
        /// The kind of host: moonraker (Klipper) or octoprint.
        #[arg(long, value_name = "KIND")]
        to: send::HostKind,
        /// The host's address, http://HOST:PORT (Moonraker usually :7125, OctoPrint :80 or :5000).
        #[arg(long, value_name = "URL")]
        url: String,
        /// The host's API key (OctoPrint: Settings → Application Keys; Moonraker: only when this
        /// computer is not a trusted client). Default: the environment variable WEFT_HOST_KEY,
        /// which keeps it out of the shell's history.
        #[arg(long, value_name = "KEY")]
        key: Option<String>,
        /// Start printing once the host has the file.
        #[arg(long)]
        start: bool,
        /// No progress on stderr.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Analyse a G-code file (weft's or any other slicer's): time, filament, features, objects.
    Analyze {
        /// The G-code file.
        file: PathBuf,
        /// Print the full report as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Print a default design (pretty JSON) to stdout.
    New,
    /// Print the share-link fragment of a design.
    Share {
        /// The design (JSON).
        design: PathBuf,
        /// Input files, as for `run` (embedded when small enough).
        #[arg(long, value_name = "[SLOT=]FILE")]
        input: Vec<String>,
    },
    /// List the job kinds with their stages and input slots.
    Jobs,
    /// Run the benchmarks (release build recommended).
    Bench {
        /// Triangles in the slicing benchmark mesh.
        #[arg(long, default_value_t = 1_000_000)]
        triangles: usize,
        /// Size of the analyzer benchmark's G-code, MB.
        #[arg(long, default_value_t = 100)]
        gcode_mb: usize,
        /// Run only the lattice path-optimisation benchmarks (otherwise they follow the others).
        #[arg(long)]
        lattice: bool,
        /// Run only the stage-cache benchmark (full run, then a re-run after a temperature edit).
        #[arg(long)]
        cache: bool,
        /// Run only the odd-node pairing benchmark: exact vs heuristic on the 48 mm disc and on
        /// 10k- and 100k-edge layers (euler and continuous), time, cost and certified gap.
        #[arg(long)]
        pairing: bool,
        /// Run only the scaling benchmark: every parser and stage at 1×, 4× and 16× its input,
        /// time and peak memory, with the growth exponent of each.
        #[arg(long)]
        scaling: bool,
        /// Run only the graded job's benchmark (issue 11): a 182 × 197 × 107 DICOM series
        /// loaded and its surface extracted; a 50 MB PrusaSlicer-style G-code edited.
        #[arg(long)]
        graded: bool,
        /// Run only the papers' table: each paper's checkable numbers beside weft's, how weft's
        /// is measured, whether the input is the paper's or weft's stand-in (a Markdown table).
        #[arg(long)]
        papers: bool,
        /// Run only these designs, each timed stage by stage (best of 3 runs, no cache): e.g.
        /// the axisymmetric examples.
        #[arg(long, num_args = 1..)]
        design: Vec<String>,
        /// One scaling case in this process (used by --scaling, one child per measurement).
        #[arg(long, hide = true)]
        scaling_case: Option<String>,
        /// The scale of --scaling-case.
        #[arg(long, hide = true, default_value_t = 1)]
        scale: usize,
    },
    /// Write one of a job's views (`weft jobs` lists them): a mesh view as a binary STL (the
    /// graded job's surface model), any other as JSON with its data.
    Inspect {
        /// The design (JSON), or a share link / fragment.
        design: String,
        /// The view's id (e.g. surface, axial).
        #[arg(long)]
        view: String,
        /// Which picture of the view (slice, layer…), from 1.
        #[arg(long, default_value_t = 1)]
        index: usize,
        /// Input files, as for `run`.
        #[arg(long, value_name = "[SLOT=]FILE")]
        input: Vec<String>,
        /// Override a design field, as for `run`.
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Output file, or a folder to write <design name>-<view>.stl / .json in.
        #[arg(long, short)]
        out: PathBuf,
    },
    /// "How it works": the design's method step by step (each step's view, what it shows and
    /// the paper's section), each drawn on the design; with --out, each step's view as JSON
    /// (a step that iterates: its first and last frames).
    Steps {
        /// The design (JSON), or a share link / fragment.
        design: String,
        /// Input files, as for `run`.
        #[arg(long, value_name = "[SLOT=]FILE")]
        input: Vec<String>,
        /// Override a design field, as for `run`.
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// A folder to write <design name>-step<N>-<view>[-last].json in.
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Write a lattice design's printed struts as an STL (a nozzle-wide prism per strut, round-capped at joints) for other slicers.
    ExportStl {
        /// The design (JSON, a lattice job).
        design: String,
        /// Output STL, or a folder to write <design name>.stl in.
        #[arg(long)]
        out: PathBuf,
    },
}

/// `println!` through [`emit`].
macro_rules! outln {
    ($($t:tt)*) => { emit(format_args!("{}\n", format_args!($($t)*))) };
}
/// `print!` through [`emit`].
macro_rules! out {
    ($($t:tt)*) => { emit(format_args!($($t)*)) };
}
/// `eprintln!` through [`emit_err`].
macro_rules! errln {
    ($($t:tt)*) => { emit_err(format_args!("{}\n", format_args!($($t)*))) };
}
/// `eprint!` through [`emit_err`].
macro_rules! err {
    ($($t:tt)*) => { emit_err(format_args!($($t)*)) };
}

/// Writes to stdout. A closed pipe (`weft analyze x.gcode --json | head`) ends the program
/// quietly with success: the reader has what it wanted. Any other failure is one error line.
fn emit(args: std::fmt::Arguments) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        errln!("weft: error: cannot write the output: {}", io_words(&e));
        std::process::exit(1);
    }
}

/// Writes to stderr, ignoring a closed stderr (there is nowhere left to say anything).
fn emit_err(args: std::fmt::Arguments) {
    use std::io::Write;
    let _ = std::io::stderr().lock().write_fmt(args);
}

/// A file-system error in words (not "No such file or directory (os error 2)").
fn io_words(e: &std::io::Error) -> String {
    use std::io::ErrorKind as K;
    match e.kind() {
        K::NotFound => "there is no such file or folder".into(),
        K::PermissionDenied => "permission denied: this user may not read or write it".into(),
        K::IsADirectory => "it is a folder, not a file".into(),
        K::NotADirectory => "a part of the path is a file, not a folder".into(),
        K::AlreadyExists => "it already exists".into(),
        K::StorageFull => "the disk is full".into(),
        K::ReadOnlyFilesystem => "the disk is read-only".into(),
        K::OutOfMemory => "out of memory".into(),
        K::FileTooLarge => "the file is too large for this file system".into(),
        K::BrokenPipe => "the reader of the output went away".into(),
        _ => {
            // The system's own words, without Rust's "(os error N)".
            let text = e.to_string();
            let text = text.split(" (os error").next().unwrap_or(&text).to_string();
            let mut c = text.chars();
            c.next().map_or(text.clone(), |f| f.to_lowercase().collect::<String>() + c.as_str())
        }
    }
}

fn read(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{}: cannot read it: {}", path.display(), io_words(&e)))
}

/// The first `max` bytes of `path` (all of a shorter file).
fn read_at_most(path: &Path, max: u64) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path).and_then(|f| f.take(max).read_to_end(&mut bytes)).map_err(|e| format!("{}: cannot read it: {}", path.display(), io_words(&e)))?;
    Ok(bytes)
}

/// A file its slot would refuse anyway (a mesh over the import's limits, volume files or
/// G-code over theirs: [`weft::kinds::SlotKind::check_file`]), refused from its head and size
/// before it is read into memory.
fn refuse_huge_file(kind: Option<weft::kinds::SlotKind>, path: &Path, name: &str) -> Result<(), String> {
    use std::io::Read;
    let Some(kind) = kind else { return Ok(()) };
    let Ok(mut file) = std::fs::File::open(path) else { return Ok(()) };
    let len = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut head = Vec::with_capacity(weft::kinds::FILE_HEAD_BYTES);
    if file.by_ref().take(weft::kinds::FILE_HEAD_BYTES as u64).read_to_end(&mut head).is_err() {
        // The full read that follows names the problem.
        return Ok(());
    }
    kind.check_file(name, &head, len)
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), String> {
    std::fs::write(path, bytes).map_err(|e| format!("{}: cannot write it: {}", path.display(), io_words(&e)))
}

/// Where to write an output named after the design: `out` as given, inside `out` when it is a
/// folder (made when the name ends in `/` and it is not there yet), else in the current
/// folder. The file's name comes from `design::file_stem`: a design or share link is untrusted
/// and its name must not choose the folder.
fn output_path(out: Option<&Path>, design_name: &str, extension: &str) -> PathBuf {
    let file = format!("{}.{extension}", weft::design::file_stem(design_name));
    match out {
        Some(dir) if dir.is_dir() => dir.join(file),
        Some(dir) if names_a_folder(dir) => {
            // A failure here is said by the write that follows, naming the file.
            let _ = std::fs::create_dir_all(dir);
            dir.join(file)
        }
        Some(path) => path.to_path_buf(),
        None => PathBuf::from(file),
    }
}

/// Whether `path` is written as a folder: its name ends in a path separator.
fn names_a_folder(path: &Path) -> bool {
    path.as_os_str().to_string_lossy().ends_with(std::path::is_separator)
}

fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// A design read from a file or a share link, with the name its problems are named after.
fn load_design(arg: &str) -> Result<(Design, String), String> {
    if arg.contains("#d=") || arg.starts_with("d=") {
        return share::decode(arg).map(|d| (d, "the share link".to_string())).map_err(|e| e.to_string());
    }
    let path = Path::new(arg);
    // A file over the limit is refused from its size, before it is read.
    let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    if len > weft::design::MAX_DESIGN_BYTES as u64 {
        return Err(weft::design::Error::TooLarge { source_name: file_name(path), bytes: usize::try_from(len).unwrap_or(usize::MAX) }.to_string());
    }
    let bytes = read_at_most(path, weft::design::MAX_DESIGN_BYTES as u64 + 1)?;
    let text = String::from_utf8(bytes).map_err(|_| format!("{arg}: this is not a design: a design is a JSON text file and this is not text"))?;
    // Checked across fields once its inputs and --set are applied (`apply_changes`).
    Design::from_json_draft(&file_name(path), &text).map(|d| (d, file_name(path))).map_err(|e| e.to_string())
}

/// A design with nothing to apply, checked across fields.
fn load_valid(arg: &str) -> Result<Design, String> {
    apply_changes(&load_design(arg)?, &[], &[], &mut Files::new())
}

/// The slot and the path of `--input [SLOT=]FILE` (the kind's first slot when none is named).
fn input_slot(kind_name: &str, kind: &dyn weft::kinds::JobKind, arg: &str) -> Result<(String, PathBuf), String> {
    match arg.split_once('=') {
        Some((slot, path)) if kind.slots().iter().any(|s| s.name == slot) => Ok((slot.to_string(), PathBuf::from(path))),
        Some((slot, _)) if !Path::new(arg).exists() => {
            let names: Vec<&str> = kind.slots().iter().map(|s| s.name).collect();
            Err(format!(
                "--input {arg}: a {kind_name} job has no input slot '{slot}'; its slots are {}",
                if names.is_empty() { "none".into() } else { names.join(", ") }
            ))
        }
        _ => {
            let first = kind.slots().first().ok_or_else(|| format!("--input: a {kind_name} job takes no input file"))?;
            Ok((first.name.to_string(), PathBuf::from(arg)))
        }
    }
}

/// `design` with every `--input [SLOT=]FILE` read into `files` and put in its slot and every
/// `--set` applied, validated once at the end (as the page does): files given one by one, as
/// a folder or in any order with the settings make the same design.
fn apply_changes((design, source): &(Design, String), inputs: &[String], set: &[String], files: &mut Files) -> Result<Design, String> {
    let registry = Registry::builtin();
    let kind_name = design.kind_after(set);
    let slots = read_inputs(&registry, &kind_name, inputs, files)?;
    let source = if set.is_empty() { source.clone() } else { "--set".to_string() };
    design.with_changes_from(&registry, &source, &slots, set).map_err(|e| e.to_string())
}

/// Reads each `--input [SLOT=]FILE` of a `kind_name` job into `files`: each slot's input, in
/// the order the slots were first named. A slot that takes several files gathers every file
/// given for it (repeated --input, folders) into one input.
fn read_inputs(registry: &Registry, kind_name: &str, inputs: &[String], files: &mut Files) -> Result<Vec<(String, weft::design::Input)>, String> {
    use weft::design::Input;
    if inputs.is_empty() {
        return Ok(Vec::new());
    }
    let kind = registry.get(kind_name).ok_or_else(|| format!("unknown job kind '{kind_name}'"))?;
    // A volume's series is read whole: the sizes of all its files, however they are given
    // (folders, repeated --input), are checked together before any is read.
    let mut series_bytes: std::collections::BTreeMap<String, u64> = std::collections::BTreeMap::new();
    for arg in inputs {
        let (slot, path) = input_slot(kind_name, kind, arg)?;
        if kind.slots().iter().any(|s| s.name == slot && s.kind == weft::kinds::SlotKind::Volume) {
            let size = |p: &Path| std::fs::metadata(p).map_or(0, |m| m.len());
            let (bytes, what) = if path.is_dir() {
                (files_in_folder(&path)?.iter().map(|(_, f)| size(f)).fold(0u64, u64::saturating_add), format!("{} (all its files)", file_name(&path)))
            } else {
                (size(&path), file_name(&path))
            };
            weft::kinds::SlotKind::Volume.check_file(&what, &[], bytes)?;
            let total = series_bytes.entry(slot.clone()).or_default();
            *total = total.saturating_add(bytes);
            weft::kinds::SlotKind::Volume.check_file(&format!("the files given for '{slot}'"), &[], *total)?;
        }
    }
    // Per slot: the names given and whether a folder was among them.
    let mut gathered: Vec<(String, Vec<String>, bool)> = Vec::new();
    for arg in inputs {
        let (slot, path) = input_slot(kind_name, kind, arg)?;
        let slot_kind = kind.slots().iter().find(|s| s.name == slot).map(|s| s.kind);
        let several = slot_kind.is_some_and(|k| k.multiple());
        let mut names = Vec::new();
        if several && path.is_dir() {
            // A folder (a DICOM series, region meshes) gives every file in it, named by its
            // path inside the folder.
            let folder = files_in_folder(&path)?;
            for (name, file) in &folder {
                refuse_huge_file(slot_kind, file, name)?;
            }
            for (name, file) in folder {
                files.insert(name.clone(), read(&file)?);
                names.push(name);
            }
            if names.is_empty() {
                return Err(format!("--input {arg}: the folder has no files"));
            }
        } else {
            let name = file_name(&path);
            refuse_huge_file(slot_kind, &path, &name)?;
            files.insert(name.clone(), read(&path)?);
            names.push(name);
        }
        let folder = several && path.is_dir();
        match gathered.iter_mut().find(|(s, _, _)| *s == slot) {
            // One file per slot: the last given wins.
            Some((_, list, _)) if !several => *list = names,
            Some((_, list, had_folder)) => {
                for n in names {
                    if !list.contains(&n) {
                        list.push(n);
                    }
                }
                *had_folder |= folder;
            }
            None => gathered.push((slot, names, folder)),
        }
    }
    Ok(gathered
        .into_iter()
        .map(|(slot, names, folder)| {
            let input = match names.as_slice() {
                [one] if !folder => Input::File { name: one.clone(), embedded: None },
                all if kind.slots().iter().any(|s| s.name == slot && s.kind.multiple()) => Input::Files(all.to_vec()),
                all => Input::File { name: all.last().cloned().unwrap_or_default(), embedded: None },
            };
            (slot, input)
        })
        .collect())
}

/// The files under `folder` (depth ≤ 8, hidden ones skipped), sorted, each with its path
/// inside the folder as its name (`/`-separated).
fn files_in_folder(folder: &Path) -> Result<Vec<(String, PathBuf)>, String> {
    const MAX_FILES: usize = 20_000;
    let mut out = Vec::new();
    let mut stack = vec![(folder.to_path_buf(), String::new(), 0usize)];
    while let Some((dir, prefix, depth)) = stack.pop() {
        let entries = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue;
            }
            let path = entry.path();
            if path.is_dir() {
                if depth < 8 {
                    stack.push((path, format!("{prefix}{name}/"), depth + 1));
                }
            } else if path.is_file() {
                out.push((format!("{prefix}{name}"), path));
                if out.len() > MAX_FILES {
                    return Err(format!("{}: more than {MAX_FILES} files; give the series' own folder", folder.display()));
                }
            }
        }
    }
    out.sort();
    Ok(out)
}

fn cmd_inspect(design: &str, view: &str, index: usize, inputs: &[String], set: &[String], out: PathBuf) -> Result<(), String> {
    let mut files = Files::new();
    let design = apply_changes(&load_design(design)?, inputs, set, &mut files)?;
    let registry = Registry::builtin();
    let found = weft::pipeline::inspect(&registry, &mut weft::pipeline::Cache::disabled(), &design, &files, view, index.saturating_sub(1))
        .map_err(|e| e.to_string())?;
    if found.shape == weft::kinds::Shape::Mesh {
        let mesh = weft::geom::Mesh::from_triangle_floats(&found.data);
        let path = output_path(Some(&out), &format!("{}-{view}", design.name), "stl");
        write(&path, &weft::isosurface::write_stl(&mesh, &design.name))?;
        errln!("{}: {} triangles", path.display(), mesh.triangles.len());
    } else {
        let path = output_path(Some(&out), &format!("{}-{view}", design.name), "json");
        let mut v = serde_json::to_value(&found).map_err(|e| e.to_string())?;
        v["data"] = serde_json::json!(found.data);
        if !found.overlay.is_empty() {
            v["overlay"] = serde_json::json!(found.overlay);
        }
        write(&path, serde_json::to_string(&v).map_err(|e| e.to_string())?.as_bytes())?;
        errln!("{}: {} {} of {} ({} values)", path.display(), view, found.index + 1, found.count, found.data.len());
    }
    Ok(())
}

/// `weft steps`: each step of the design's method with what it drew (the view's caption);
/// with `out`, each step's view as JSON, a scrubbing step's first and last frames.
fn cmd_steps(design: &str, inputs: &[String], set: &[String], out: Option<&Path>) -> Result<(), String> {
    let mut files = Files::new();
    let design = apply_changes(&load_design(design)?, inputs, set, &mut files)?;
    let registry = Registry::builtin();
    let kind = registry.get(design.job.kind()).ok_or_else(|| format!("job kind {} is not known (weft jobs lists them)", design.job.kind()))?;
    if kind.steps().is_empty() {
        return Err(format!("the {} job has no steps to show (the lattice, axisymmetric, graded, foam and freeform jobs have)", kind.name()));
    }
    // One cache for all steps: the stages they share run once.
    let mut cache = weft::pipeline::Cache::new();
    for (n, step) in kind.steps().iter().enumerate() {
        let first = weft::pipeline::inspect(&registry, &mut cache, &design, &files, step.view, step.index)
            .map_err(|e| format!("step {} ({}): {e}", n + 1, step.title))?;
        let caption = first.meta.get("caption").and_then(|c| c.as_str()).unwrap_or("");
        outln!(
            "{}. {}  [{} {}{}]",
            n + 1,
            step.title,
            step.view,
            first.index + 1,
            if step.scrub { format!(" of {} frames", first.count) } else { String::new() }
        );
        outln!("   {}", step.text);
        outln!("   paper: {}", step.cite);
        if !caption.is_empty() {
            outln!("   drawn: {caption}");
        }
        let Some(dir) = out else { continue };
        let mut frames = vec![("", first)];
        if step.scrub && frames[0].1.count > 1 {
            let last = weft::pipeline::inspect(&registry, &mut cache, &design, &files, step.view, frames[0].1.count - 1).map_err(|e| e.to_string())?;
            frames.push(("-last", last));
        }
        for (suffix, found) in frames {
            let path = dir.join(format!("{}-step{}-{}{suffix}.json", design.name, n + 1, step.view));
            let mut v = serde_json::to_value(&found).map_err(|e| e.to_string())?;
            v["data"] = serde_json::json!(found.data);
            v["step"] = serde_json::json!({ "number": n + 1, "title": step.title, "text": step.text, "cite": step.cite });
            if !found.overlay.is_empty() {
                v["overlay"] = serde_json::json!(found.overlay);
            }
            write(&path, serde_json::to_string(&v).map_err(|e| e.to_string())?.as_bytes())?;
            errln!("{}: {} {} of {} ({} values)", path.display(), step.view, found.index + 1, found.count, found.data.len());
        }
    }
    Ok(())
}

/// Sizes the pool the parallel loops run on ([`weft::par`]): `n` threads, or every core.
fn use_threads(n: Option<usize>) -> Result<(), String> {
    match n {
        Some(0) => Err("--threads 0: give at least 1 (or leave it out for every core)".into()),
        Some(n) if n > 1024 => Err(format!("--threads {n}: at most 1024")),
        _ => rayon::ThreadPoolBuilder::new().num_threads(n.unwrap_or(0)).build_global().map_err(|e| format!("--threads: {e}")),
    }
}

// One parameter per `weft run` option, as clap's `Command::Run` hands them over.
#[allow(clippy::too_many_arguments)]
fn cmd_run(
    design: &str,
    out: Option<PathBuf>,
    report: Option<PathBuf>,
    ahead: Option<PathBuf>,
    inputs: &[String],
    set: &[String],
    printer: Option<&str>,
    quiet: bool,
    dry_run: bool,
    send_opts: SendOptions,
) -> Result<(), String> {
    let mut design = load_design(design)?;
    if let Some(id) = printer {
        design.0.printer = weft::gcode::presets::preset(id).map_err(|e| format!("--printer: {e}"))?.printer;
    }
    let mut files = Files::new();
    let mut design = apply_changes(&design, inputs, set, &mut files)?;
    // Binary G-code when the output's name ends in .bgcode, text when it ends in .gcode, else
    // what the printer asks for (printer.binary_gcode): decided, and refused, before any work.
    let named = |ext: &str| out.as_deref().is_some_and(|p| !p.is_dir() && !names_a_folder(p) && p.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)));
    let (named_binary, named_text) = (named("bgcode"), named("gcode"));
    if named_binary && design.printer.flavor != weft::gcode::Flavor::Marlin {
        return Err(format!(
            "{}: binary G-code is Marlin G-code; the {} flavour writes .{}",
            out.as_deref().map(Path::display).map(|d| d.to_string()).unwrap_or_default(),
            design.printer.flavor.name(),
            design.printer.flavor.file_extension()
        ));
    }
    if named_text {
        // The text is the same either way; the run then makes no .bgcode only to drop it.
        design.printer.binary_gcode = false;
    }
    if dry_run {
        let plan = pipeline::estimate(&Registry::builtin(), &mut pipeline::Cache::disabled(), &design, &files).map_err(|e| e.to_string())?;
        out!("{}", plan_table(&plan));
        if let Some(path) = report {
            write(&path, serde_json::to_string_pretty(&plan).unwrap_or_default().as_bytes())?;
        }
        return match plan.refused {
            Some((stage, r)) => Err(format!("{stage}: {r}")),
            None => Ok(()),
        };
    }
    // The page asks before a big job; the CLI runs it, saying what it is first. The cache keeps
    // the imports the estimate read for the run.
    let registry = Registry::builtin();
    let mut cache = pipeline::Cache::new();
    if !quiet {
        if let Ok(plan) = pipeline::estimate(&registry, &mut cache, &design, &files) {
            if let Some(ask) = plan.ask.as_deref().filter(|_| plan.refused.is_none()) {
                eprintln!("weft: {ask} (weft run --dry-run states every stage)");
            }
        }
    }
    let show = !quiet && std::io::stderr().is_terminal();
    let mut last = (String::new(), -1i32);
    let mut progress = |stage: &str, f: f32| {
        let pct = (f * 100.0) as i32;
        if show && (stage != last.0 || pct / 10 != last.1 / 10) {
            err!("\r{:<10} {:>3}%", stage, pct);
            last = (stage.to_string(), pct);
        }
    };
    let started = std::time::Instant::now();
    let ahead_path = ahead.map(|p| output_path(Some(&p), &design.name, &format!("ahead.{}", design.printer.flavor.file_extension())));
    let ahead_failed = std::cell::RefCell::new(None);
    let send = |a: &pipeline::Ahead| {
        let written = ahead_path.as_ref().map(|p| write(p, a.gcode.as_bytes()).map(|_| p));
        if !quiet {
            let to = match &written {
                Some(Ok(p)) => format!(" → {}", p.display()),
                _ => " (--ahead FILE writes it)".into(),
            };
            errln!(
                "\r{}: sent ahead {} ({} of G-code) at {:.2} s{to}",
                a.stage,
                a.label,
                weft::budget::human(a.gcode.len() as f64, "bytes"),
                started.elapsed().as_secs_f64()
            );
        }
        if let Some(Err(e)) = written {
            *ahead_failed.borrow_mut() = Some(e);
        }
    };
    let result = pipeline::run_sending(&registry, &mut cache, &design, &files, &RunOptions::default(), &mut progress, &send);
    if show {
        err!("\r                \r");
    }
    let output = result.map_err(|e| e.to_string())?;
    if let Some(e) = ahead_failed.into_inner() {
        return Err(format!("--ahead: {e}"));
    }
    let binary = output.bgcode.clone().or_else(|| named_binary.then(|| std::sync::Arc::new(weft::gcode::binary::from_text(&output.gcode))));
    let extension = if binary.is_some() { "bgcode" } else { design.printer.flavor.file_extension() };
    let out = output_path(out.as_deref(), &design.name, extension);
    match &binary {
        Some(b) => write(&out, b)?,
        None => write(&out, output.gcode.as_bytes())?,
    }
    // What the stages repaired or assumed is said even with --quiet: it changes what prints.
    for stage in &output.report.stages {
        for note in &stage.notes {
            errln!("weft: {}: {note}", stage.stage);
        }
    }
    if let Some(path) = report {
        let json = serde_json::to_string_pretty(&output.report).unwrap_or_default();
        write(&output_path(Some(&path), &design.name, "report.json"), json.as_bytes())?;
    }
    if !quiet {
        let a = &output.report.analysis;
        errln!(
            "{}: {} layers, {} paths, {:.1} mm extruded, {:.1} mm filament, {} retractions, ~{}",
            out.display(),
            a.layers,
            a.extrusion_paths,
            a.extruded_mm,
            a.filament_mm,
            a.retractions,
            hms(a.estimated_time_s)
        );
        errln!("{}", where_the_time_went(&output.report));
    }
    let written: &[u8] = match &binary {
        Some(b) => b,
        None => output.gcode.as_bytes(),
    };
    send_after_run(send_opts, written, &out, quiet)
}

/// One line: each stage's wall time, the slowest first, and the threads used.
fn where_the_time_went(r: &weft::pipeline::RunReport) -> String {
    let mut t: Vec<&weft::pipeline::StageTime> = r.timings.iter().filter(|t| !t.cached && t.ms >= 0.5).collect();
    t.sort_by(|a, b| b.ms.total_cmp(&a.ms));
    let parts: Vec<String> = t.iter().map(|t| format!("{} {}", t.stage, weft::budget::human(t.ms / 1000.0, "s"))).collect();
    let threads = if r.threads == 1 { "1 thread".to_string() } else { format!("{} threads", r.threads) };
    format!("time: {} ({threads})", if parts.is_empty() { "nothing measurable".into() } else { parts.join(", ") })
}

/// `weft bench --design FILE…`: each design timed stage by stage, at 1 thread and at every
/// core (the G-code is the same bytes).
#[cfg(feature = "bench")]
fn design_bench(paths: &[String]) -> Result<(), String> {
    let mut rows = Vec::new();
    for p in paths {
        rows.push(load_valid(p).and_then(|d| weft::bench::designs::time_design_threads(&d, 3))?);
    }
    outln!("{}", weft::bench::designs::threads_table(&rows, rayon::current_num_threads()));
    Ok(())
}

/// The plan as a table: one line per stage (its counts, peak memory, time), then the totals.
fn plan_table(plan: &weft::budget::Plan) -> String {
    use weft::budget::human;
    let n = plan.threads;
    let threads = |n: usize| format!("{n} thread{}", if n == 1 { "" } else { "s" });
    let mut out = format!("{:<10} {:>10} {:>9} {:>10}  {}\n", "stage", "memory", "1 thread", threads(n), "work");
    for e in &plan.stages {
        let work: Vec<String> = e.quantities.iter().map(|q| format!("{} {}", q.label.to_lowercase(), human(q.value, q.unit))).collect();
        out +=
            &format!("{:<10} {:>10} {:>9} {:>10}  {}\n", e.stage, human(e.bytes, "bytes"), human(e.seconds, "s"), human(e.seconds_on(n), "s"), work.join(", "));
    }
    out += &format!(
        "total: about {} on {} ({} on 1), peak {}, {} segments, {} of G-code\n",
        human(plan.wall_seconds, "s"),
        threads(n),
        human(plan.seconds, "s"),
        human(plan.peak_bytes, "bytes"),
        human(plan.segments, ""),
        human(plan.gcode_bytes, "bytes")
    );
    if let Some(ask) = &plan.ask {
        out += &format!("{ask} (the page asks before running it)\n");
    }
    if plan.refused.is_none() {
        out += "within the budgets\n";
    }
    out
}

fn hms(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    format!("{}h {:02}m {:02}s", s / 3600, s / 60 % 60, s % 60)
}

fn cmd_analyze(file: &Path, json: bool) -> Result<(), String> {
    // A file over the analyzer's limit is refused from its size, before it is read.
    if let Ok(meta) = std::fs::metadata(file) {
        weft::analyze::check_size(&file_name(file), meta.len()).map_err(|e| e.to_string())?;
    }
    let bytes = read(file)?;
    let analysis = weft::analyze::analyze(&file_name(file), &bytes, &Default::default()).map_err(|e| e.to_string())?;
    let r = &analysis.report;
    if json {
        outln!("{}", serde_json::to_string_pretty(r).unwrap_or_default());
    } else {
        outln!("layers            {}", r.layers);
        outln!("extrusion paths   {}", r.extrusion_paths);
        outln!("extruded          {:.3} mm", r.extruded_mm);
        outln!("travel            {:.3} mm", r.travel_mm);
        outln!("retractions       {}", r.retractions);
        outln!("overlap           {:.3} mm", r.overlap_mm);
        outln!("GIPPO score       {:.4}", r.gippo_score);
        outln!("estimated time    {} ({:.0} s)", hms(r.estimated_time_s), r.estimated_time_s);
        outln!("filament          {:.3} mm", r.filament_mm);
    }
    Ok(())
}

fn cmd_share(design: &Path, inputs: &[String]) -> Result<(), String> {
    let mut files = Files::new();
    let d = apply_changes(&load_design(&design.display().to_string())?, inputs, &[], &mut files)?;
    let list: Vec<(&str, &[u8])> = files.names().filter_map(|n| files.get(n).map(|b| (n, b))).collect();
    let link = share::encode(&d, &list);
    outln!("{}", link.fragment);
    if !link.note.is_empty() {
        errln!("note: {}", link.note);
    }
    Ok(())
}

fn cmd_jobs() {
    for k in Registry::builtin().kinds() {
        outln!("{:<10} {}", k.name(), k.doc());
        let stages: Vec<&str> = k.stages().iter().map(|s| s.name).collect();
        outln!("  stages: {} → gcode → analyze", stages.join(" → "));
        for s in k.slots() {
            let what = if s.kind == weft::kinds::SlotKind::Volume { "FOLDER|FILE" } else { "FILE" };
            outln!("  --input {}={what}   {} ({}): {}", s.name, s.label, s.kind.accept().join(" "), s.doc);
        }
    }
}

/// This process's peak resident memory, KiB (Linux).
#[cfg(feature = "bench")]
fn peak_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// `weft bench --scaling`: each case at each scale in a child process (so each peak memory is
/// its own), then the growth exponents of time and of memory above an idle child's.
#[cfg(feature = "bench")]
fn scaling_bench() -> Result<(), String> {
    use weft::bench::scaling::{cases, exponent, MAX_EXPONENT, SCALES};
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let child = |name: &str, scale: usize| -> Result<(f64, f64, f64), String> {
        let out =
            std::process::Command::new(&exe).args(["bench", "--scaling-case", name, "--scale", &scale.to_string()]).output().map_err(|e| e.to_string())?;
        if !out.status.success() {
            return Err(format!("{name} ×{scale}: {}", String::from_utf8_lossy(&out.stderr).trim()));
        }
        let text = String::from_utf8_lossy(&out.stdout);
        let v: Vec<f64> = text.split_whitespace().filter_map(|w| w.parse().ok()).collect();
        match v[..] {
            [size, seconds, kib] => Ok((size, seconds, kib * 1024.0)),
            _ => Err(format!("{name} ×{scale}: unreadable answer '{text}'")),
        }
    };
    let idle = std::process::Command::new(&exe).args(["bench", "--scaling-case", "none"]).output().ok();
    let idle_bytes =
        idle.and_then(|o| String::from_utf8_lossy(&o.stdout).split_whitespace().nth(2).and_then(|w| w.parse::<f64>().ok())).unwrap_or(0.0) * 1024.0;
    outln!("scaling: best of 3 per size; memory = peak resident above an idle process ({:.1} MiB)", idle_bytes / 1048576.0);
    outln!("{:<20} {:>10} {:>22} {:>22} {:>22} {:>6} {:>6}", "case", "unit", "1×: size, s, MiB", "4×", "16×", "t exp", "m exp");
    let mut over = Vec::new();
    for case in cases() {
        let mut rows = Vec::new();
        for &k in &SCALES {
            rows.push(child(case.name, k)?);
        }
        let t = exponent(&rows.iter().map(|r| (r.0, r.1)).collect::<Vec<_>>());
        let m = exponent(&rows.iter().map(|r| (r.0, (r.2 - idle_bytes).max(1.0))).collect::<Vec<_>>());
        let cells: Vec<String> = rows.iter().map(|r| format!("{:.0}, {:.3}, {:.1}", r.0, r.1, (r.2 - idle_bytes).max(0.0) / 1048576.0)).collect();
        let flag = if t > MAX_EXPONENT || m > MAX_EXPONENT { " ✗" } else { "" };
        outln!("{:<20} {:>10} {:>22} {:>22} {:>22} {:>6.2} {:>6.2}{flag}", case.name, case.unit, cells[0], cells[1], cells[2], t, m);
        if !flag.is_empty() {
            over.push(case.name);
        }
    }
    if over.is_empty() {
        outln!("every exponent ≤ {MAX_EXPONENT}");
        Ok(())
    } else {
        Err(format!("growth exponent over {MAX_EXPONENT}: {}", over.join(", ")))
    }
}

/// `weft bench`: the workloads of BENCHMARKS.md.
#[cfg(feature = "bench")]
fn cmd_bench(command: Command) -> Result<(), String> {
    match command {
        Command::Bench { scaling_case: Some(name), scale, .. } => weft::bench::scaling::run_case(&name, scale).map(|(size, seconds)| {
            outln!("{size} {seconds} {}", peak_kib().unwrap_or(0));
        }),
        Command::Bench { scaling: true, .. } => scaling_bench(),
        Command::Bench { design, .. } if !design.is_empty() => design_bench(&design),
        Command::Bench { pairing: true, .. } => weft::bench::pairing::run_all().map(|t| outln!("{t}")),
        Command::Bench { papers: true, .. } => weft::bench::papers::run_all().map(|t| outln!("{t}")),
        Command::Bench { graded: true, .. } => weft::bench::graded::run_graded().map(|t| outln!("{t}")),
        Command::Bench { triangles, gcode_mb, lattice, cache, .. } => {
            if cache {
                return weft::bench::run_cache(triangles).map(|t| outln!("{t}"));
            }
            let all = if lattice { Ok(String::new()) } else { weft::bench::run_all(triangles, gcode_mb) };
            all.and_then(|a| weft::bench::run_lattice().map(|l| outln!("{a}\n{l}")))
        }
        _ => Err("not a bench command".into()),
    }
}

/// `weft bench` in a build without the `bench` feature (a library build with
/// `--no-default-features`): says how to get it.
#[cfg(not(feature = "bench"))]
fn cmd_bench(_: Command) -> Result<(), String> {
    Err("this weft was built without its benchmarks (feature `bench`): build it with `cargo build --release` (the default features)".into())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run { design, out, report, input, set, printer, threads, ahead, quiet, dry_run, send } => {
            if let Err(e) = use_threads(threads) {
                errln!("weft: error: {e}");
                return ExitCode::from(2);
            }
            if dry_run && send.send_to.is_some() {
                errln!("weft: error: --send-to sends the G-code a run writes, and --dry-run writes none: leave one out");
                return ExitCode::from(2);
            }
            cmd_run(&design, out, report, ahead, &input, &set, printer.as_deref(), quiet, dry_run, send)
        }
        Command::Send { file, to, url, key, start, quiet } => cmd_send(&file, to, &url, key, start, quiet),
        Command::Analyze { file, json } => cmd_analyze(&file, json),
        Command::New => {
            let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
            out!("{}", Design { date: weft::gcode::utc_date(now), ..Design::default() }.to_json_pretty());
            Ok(())
        }
        Command::Share { design, input } => cmd_share(&design, &input),
        Command::Jobs => {
            cmd_jobs();
            Ok(())
        }
        bench @ Command::Bench { .. } => cmd_bench(bench),
        Command::Inspect { design, view, index, input, set, out } => cmd_inspect(&design, &view, index, &input, &set, out),
        Command::Steps { design, input, set, out } => cmd_steps(&design, &input, &set, out.as_deref()),
        Command::ExportStl { design, out } => load_valid(&design).and_then(|d| {
            let e = weft::export::lattice_stl(&d).map_err(|e| e.to_string())?;
            let out = output_path(Some(&out), &d.name, "stl");
            write(&out, &e.stl)?;
            errln!("{}: {} struts, {} triangles, {:.3} mm of struts", out.display(), e.struts, e.triangles, e.strut_mm);
            Ok(())
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            errln!("weft: error: {}", e.replace('\n', "; "));
            ExitCode::FAILURE
        }
    }
}

/// `weft run`'s options that send the G-code to a print host once it is written.
#[derive(clap::Args, Default)]
struct SendOptions {
    /// Send the G-code to this print host after writing it: moonraker (Klipper) or octoprint.
    #[arg(long, visible_alias = "send", value_name = "KIND", requires = "send_url")]
    send_to: Option<send::HostKind>,
    /// The print host's address, http://HOST:PORT (Moonraker usually :7125, OctoPrint :80 or :5000).
    #[arg(long, value_name = "URL", requires = "send_to")]
    send_url: Option<String>,
    /// The host's API key (OctoPrint: Settings → Application Keys; Moonraker: only when this
    /// computer is not a trusted client). Default: the environment variable WEFT_HOST_KEY,
    /// which keeps it out of the shell's history.
    #[arg(long, value_name = "KEY", requires = "send_to")]
    send_key: Option<String>,
    /// Start printing once the host has the file.
    #[arg(long, requires = "send_to")]
    send_start: bool,
}

/// The API key given, else WEFT_HOST_KEY's (an empty one is none).
fn host_key(given: Option<String>) -> Option<String> {
    given.or_else(|| std::env::var("WEFT_HOST_KEY").ok()).map(|k| k.trim().to_string()).filter(|k| !k.is_empty())
}

/// `weft send FILE --to KIND --url URL [--key KEY] [--start]`.
fn cmd_send(file: &Path, to: send::HostKind, url: &str, key: Option<String>, start: bool, quiet: bool) -> Result<(), String> {
    let bytes = read(file)?;
    let name = file.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "weft.gcode".into());
    send_gcode(&bytes, &name, to, url, host_key(key).as_deref(), start, quiet)
}

/// Sends `bytes` as `name` with progress on stderr (`weft: send: 45 % (1.2 MiB of 2.7 MiB)`),
/// then says what the host did and its job state. The key is never printed.
fn send_gcode(bytes: &[u8], name: &str, to: send::HostKind, url: &str, key: Option<&str>, start: bool, quiet: bool) -> Result<(), String> {
    let terminal = std::io::stderr().is_terminal();
    // A terminal sees the line change; a log gets a line at every quarter.
    let mut shown: Option<u64> = None;
    let mut progress = |sent: u64, total: u64| {
        if quiet {
            return;
        }
        let pct = (sent * 100).checked_div(total).unwrap_or(100);
        let step = if terminal { pct } else { pct / 25 * 25 };
        if shown == Some(step) {
            return;
        }
        shown = Some(step);
        let line = format!("weft: send: {pct} % ({} of {})", send::size(sent), send::size(total));
        if terminal {
            err!("\r{line:<60}");
        } else {
            errln!("{line}");
        }
    };
    let result = send::send(bytes, name, to, url, key, start, &mut progress);
    if terminal && shown.is_some() {
        err!("\r{:<60}\r", "");
    }
    let sent = result.map_err(|e| e.to_string())?;
    let started = if sent.started { "; printing started" } else { "" };
    errln!("weft: sent {} to {} {} ({} in {:.1} s){started}", sent.name, to.label(), sent.host, send::size(sent.bytes), sent.seconds);
    if start {
        // The host needs a moment to begin the job it was given.
        std::thread::sleep(std::time::Duration::from_millis(1000));
    }
    match send::job_state(to, url, key) {
        Ok(job) => errln!("weft: host {job}"),
        Err(e) => errln!("weft: send: no job state: {e}"),
    }
    Ok(())
}

/// After `weft run` wrote its G-code: sends it when --send-to asks.
fn send_after_run(opts: SendOptions, gcode: &[u8], out: &Path, quiet: bool) -> Result<(), String> {
    let (Some(to), Some(url)) = (opts.send_to, opts.send_url.as_deref()) else { return Ok(()) };
    let name = out.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "weft.gcode".into());
    send_gcode(gcode, &name, to, url, host_key(opts.send_key).as_deref(), opts.send_start, quiet)
}
