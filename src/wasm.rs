//! The only module that knows about JavaScript (compiled for wasm32 only).
//!
//! Free functions serve the page's cheap synchronous needs (schema, validation, share
//! links); [`Session`] lives in the Web Worker, holds loaded files and the last result, and
//! hands out preview buffers as typed arrays (copied once out of wasm memory, then
//! transferred, not copied, to the page).

use crate::analyze;
use crate::design::{schema, share, Design};
use crate::import;
use crate::pipeline::{self, Files, RunOptions};
use wasm_bindgen::prelude::*;

#[wasm_bindgen(start)]
fn start() {
    console_error_panic_hook::set_once();
}

fn js_err(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

/// A default design (pretty JSON).
#[wasm_bindgen(js_name = defaultDesign)]
pub fn default_design() -> String {
    Design::default().to_json_pretty()
}

/// The field table the form is built from (JSON).
#[wasm_bindgen(js_name = designSchema)]
pub fn design_schema() -> String {
    schema::schema_json()
}

/// Parses and validates a design; returns it normalised (pretty JSON).
#[wasm_bindgen(js_name = validateDesign)]
pub fn validate_design(json: &str) -> Result<String, JsError> {
    Design::from_json("design", json).map(|d| d.to_json_pretty()).map_err(js_err)
}

/// Sets one field (`path` dotted, `value` JSON or plain text) and returns the new design.
#[wasm_bindgen(js_name = setField)]
pub fn set_field(json: &str, path: &str, value: &str) -> Result<String, JsError> {
    let d = Design::from_json("design", json).map_err(js_err)?;
    d.with_overrides(&[format!("{path}={value}")]).map(|d| d.to_json_pretty()).map_err(|e| match e {
        // The page edits one field at a time: name it, not the CLI's `--set` form.
        crate::design::Error::Override { message, .. } => JsError::new(&format!("{path}: {message}")),
        other => js_err(other),
    })
}

/// A share-link fragment for the design (JSON `{fragment, embedded, note}`).
#[wasm_bindgen(js_name = encodeShare)]
pub fn encode_share(design_json: &str, file_name: Option<String>, file_bytes: Option<Vec<u8>>) -> Result<String, JsError> {
    let mut d = Design::from_json("design", design_json).map_err(js_err)?;
    if let (Some(name), Some(slot)) = (file_name, d.job.input_mut()) {
        *slot = crate::design::Input::File { name, embedded: None };
    }
    let link = share::encode(&d, file_bytes.as_deref());
    serde_json::to_string(&link).map_err(js_err)
}

/// The design in a share-link fragment (pretty JSON).
#[wasm_bindgen(js_name = decodeShare)]
pub fn decode_share(fragment: &str) -> Result<String, JsError> {
    share::decode(fragment).map(|d| d.to_json_pretty()).map_err(js_err)
}

/// State held by the worker: loaded files and the last result.
#[wasm_bindgen]
pub struct Session {
    files: Files,
    gcode: Vec<u8>,
    preview: analyze::Preview,
    bed: [f64; 3],
}

impl Default for Session {
    fn default() -> Self {
        Self::new()
    }
}

#[wasm_bindgen]
impl Session {
    /// An empty session.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Session {
        Session { files: Files::new(), gcode: Vec::new(), preview: Default::default(), bed: Design::default().printer.bed_size_mm }
    }

    /// Reads a mesh now (so a bad file is reported at once) and keeps it; returns the import report.
    #[wasm_bindgen(js_name = addFile)]
    pub fn add_file(&mut self, name: &str, bytes: Vec<u8>) -> Result<String, JsError> {
        let imported = import::read_mesh(name, &bytes, &import::Options::default()).map_err(js_err)?;
        self.files.insert(name.to_string(), bytes);
        serde_json::to_string(&imported.report).map_err(js_err)
    }

    /// Runs a design; `on_progress(stage, fraction)`; returns the run report (JSON).
    pub fn run(&mut self, design_json: &str, on_progress: &js_sys::Function) -> Result<String, JsError> {
        let design = Design::from_json("design", design_json).map_err(js_err)?;
        let mut progress = |stage: pipeline::Stage, f: f32| {
            let _ = on_progress.call2(&JsValue::NULL, &JsValue::from_str(stage.name()), &JsValue::from_f64(f as f64));
        };
        let out = pipeline::run(&design, &self.files, &RunOptions { collect_preview: true }, &mut progress).map_err(js_err)?;
        self.gcode = out.gcode.into_bytes();
        self.preview = out.preview.unwrap_or_default();
        self.bed = design.printer.bed_size_mm;
        serde_json::to_string(&out.report).map_err(js_err)
    }

    /// Analyses a G-code file and makes it the current result; returns `{analysis}` (JSON).
    #[wasm_bindgen(js_name = analyzeGcode)]
    pub fn analyze_gcode(&mut self, name: &str, bytes: Vec<u8>) -> Result<String, JsError> {
        let options = analyze::Options { collect_preview: true, ..Default::default() };
        let a = analyze::analyze(name, &bytes, &options).map_err(js_err)?;
        self.gcode = bytes;
        self.preview = a.preview.unwrap_or_default();
        #[derive(serde::Serialize)]
        struct Out<'a> {
            analysis: &'a analyze::Report,
        }
        serde_json::to_string(&Out { analysis: &a.report }).map_err(js_err)
    }

    /// The lattice strokes of layer `layer` (0-based) of a lattice design, for the page's 2D
    /// preview: 5 floats per segment, x0 y0 x1 y1 feature-code (mm, model coordinates).
    #[wasm_bindgen(js_name = latticeLayer)]
    pub fn lattice_layer(&self, design_json: &str, layer: usize) -> Result<Vec<f32>, JsError> {
        let design = Design::from_json("design", design_json).map_err(js_err)?;
        let (layers, _) = pipeline::lattice_strokes(&design, &self.files, &mut |_, _| {}).map_err(js_err)?;
        let mut out = Vec::new();
        if let Some(l) = layers.get(layer.min(layers.len().saturating_sub(1))) {
            for s in &l.strokes {
                for w in s.points.windows(2) {
                    out.extend_from_slice(&[w[0].x as f32, w[0].y as f32, w[1].x as f32, w[1].y as f32, s.feature.code() as f32]);
                }
            }
        }
        Ok(out)
    }

    /// G-code bytes of the last result.
    pub fn gcode(&self) -> Vec<u8> {
        self.gcode.clone()
    }
    /// Extrusion segments, 6 floats each (mm).
    #[wasm_bindgen(js_name = previewPositions)]
    pub fn preview_positions(&self) -> Vec<f32> {
        self.preview.positions.clone()
    }
    /// Feature code per segment.
    #[wasm_bindgen(js_name = previewFeature)]
    pub fn preview_feature(&self) -> Vec<u8> {
        self.preview.feature.clone()
    }
    /// Path index per segment.
    #[wasm_bindgen(js_name = previewPath)]
    pub fn preview_path(&self) -> Vec<u32> {
        self.preview.path.clone()
    }
    /// Volumetric flow per segment, mm³/s.
    #[wasm_bindgen(js_name = previewFlow)]
    pub fn preview_flow(&self) -> Vec<f32> {
        self.preview.flow.clone()
    }
    /// Width per segment, mm.
    #[wasm_bindgen(js_name = previewWidth)]
    pub fn preview_width(&self) -> Vec<f32> {
        self.preview.width.clone()
    }
    /// First segment of each layer, plus the end.
    #[wasm_bindgen(js_name = previewLayerStart)]
    pub fn preview_layer_start(&self) -> Vec<u32> {
        self.preview.layer_segment_start.clone()
    }
    /// Travel segments, 6 floats each (mm).
    #[wasm_bindgen(js_name = previewTravel)]
    pub fn preview_travel(&self) -> Vec<f32> {
        self.preview.travel_positions.clone()
    }
    /// First travel segment of each layer, plus the end.
    #[wasm_bindgen(js_name = previewTravelLayerStart)]
    pub fn preview_travel_layer_start(&self) -> Vec<u32> {
        self.preview.layer_travel_start.clone()
    }
    /// Z of each layer, mm.
    #[wasm_bindgen(js_name = previewLayerZ)]
    pub fn preview_layer_z(&self) -> Vec<f32> {
        self.preview.layer_z.clone()
    }
    /// Bed size of the last run's printer, mm.
    #[wasm_bindgen(js_name = bedSize)]
    pub fn bed_size(&self) -> Vec<f64> {
        self.bed.to_vec()
    }
}

/// Segments (x0 y0 x1 y1, mm, centred on 0) of `pattern` (JSON, e.g. `{"kind":"voronoi"}`)
/// cropped to a `size_mm` square: the page's pattern thumbnails.
#[wasm_bindgen(js_name = patternThumbnail)]
pub fn pattern_thumbnail(pattern_json: &str, size_mm: f64, seed: u64) -> Result<Vec<f32>, JsError> {
    let pattern: crate::lattice::Pattern = serde_json::from_str(pattern_json).map_err(js_err)?;
    Ok(crate::lattice::thumbnail(&pattern, size_mm, seed).into_iter().flat_map(|s| s.map(|x| x as f32)).collect())
}

/// Benchmark workload: binary STL of the benchmark mesh (about `triangles` triangles).
#[wasm_bindgen(js_name = benchMeshStl)]
pub fn bench_mesh_stl(triangles: usize) -> Vec<u8> {
    crate::bench::bench_mesh(triangles).to_stl_binary()
}

/// Benchmark workload: the slicing benchmark design (JSON).
#[wasm_bindgen(js_name = benchDesign)]
pub fn bench_design() -> String {
    crate::bench::bench_design().to_json_pretty()
}

/// Benchmark workload: analyses `gcode` without preview; returns the report JSON.
#[wasm_bindgen(js_name = benchAnalyze)]
pub fn bench_analyze(gcode: &[u8]) -> Result<String, JsError> {
    let a = analyze::analyze("bench.gcode", gcode, &Default::default()).map_err(js_err)?;
    serde_json::to_string(&a.report).map_err(js_err)
}

/// Benchmark workload: one lattice path-optimisation layer (`src/bench.rs`), prepared by
/// [`BenchLattice::new`] (not timed); [`BenchLattice::run`] is the part timed in the worker.
#[wasm_bindgen]
pub struct BenchLattice(crate::bench::LatticeBench);

#[wasm_bindgen]
impl BenchLattice {
    /// Prepares `which` (`honeycomb-10mm`, `disc-48mm` or `euler-100k`).
    #[wasm_bindgen(constructor)]
    pub fn new(which: &str) -> Result<BenchLattice, JsError> {
        crate::bench::LatticeBench::prepare(which).map(BenchLattice).map_err(js_err)
    }

    /// Runs `paths::optimise` once; returns `{edges, paths, score}` as JSON.
    pub fn run(&self) -> Result<String, JsError> {
        let s = self.0.run().map_err(js_err)?;
        Ok(format!(r#"{{"edges":{},"paths":{},"score":{}}}"#, s.edges, s.paths, s.score))
    }

    /// The method (`gippo_max` or `euler`).
    pub fn method(&self) -> String {
        self.0.method().into()
    }

    /// The issue's target, ms.
    #[wasm_bindgen(js_name = targetMs)]
    pub fn target_ms(&self) -> f64 {
        self.0.target_ms()
    }
}
