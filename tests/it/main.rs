//! weft's integration tests, in one binary so the library is linked once: one module an
//! area. `cargo test --release --test it MODULE::` runs one area (e.g. `import_hostile::`).
//! Growth checks count work ([`work`]); none asserts on time.

#[global_allocator]
static ALLOC: work::Counting = work::Counting;

mod common;
mod work;

mod analyze_basic;
mod analyze_fixtures;
mod analyze_fuzz;
mod analyze_hostile;
mod architecture;
mod axisym_job;
mod axisym_tour;
mod bridges;
mod cli;
mod curved_struts;
mod design_fuzz;
mod design_hostile;
mod design_scaling;
mod estimates;
mod export_stl;
mod foam_job;
mod foam_model;
mod foam_raster;
mod freeform;
mod fuzz_smoke;
mod gcode_edit;
mod gcode_features;
mod gcode_five_axis;
mod gcode_host;
mod gcode_roundtrip;
mod gcode_timing;
mod gcode_writer;
mod golden_gcode;
mod graded_job;
mod import;
mod import_hostile;
mod import_same_bytes;
mod infill_patterns;
mod input_checks;
mod isosurface;
mod job_kinds;
mod lattice;
mod lattice_estimate;
mod lattice_pipeline;
mod nonplanar;
mod optimality;
mod papers_table;
mod path_order;
mod paths;
mod pipeline;
mod pore_fraction;
mod postman_exact;
mod ranges;
mod scaffold_model;
mod seams;
mod slice;
mod steps;
mod steps_lattice;
mod steps_methods;
mod supports;
mod threads;
mod volume_import;
mod volume_ops;
