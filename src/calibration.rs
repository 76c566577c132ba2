//! Measured properties of the executor that the planner and spec validation rely on to turn a target
//! crossing ratio into allocations.
//!
//! Not every planned crosser ends up *labelled* a crosser (C = 1 in at least one annotated frame): a crossing
//! can happen after the ego has passed or too far away to pass the visibility gate. The planner allocates
//! crossers so that the expected labelled ratio equals the target.
//!
//! Re-measure after any change to the simulation, the planner's placement or the visibility gate with
//! `cargo run --release --example realisation -- specs/balanced_50.yaml specs/pedsynth_pp.yaml` and update the
//! constant (and BENCHMARKS.md's "Crossing-rate calibration" section).

/// Share of crossers planned by layer 1 that are labelled crossers in the dataset. Measured 2026-11-21 with the
/// command above: 0.919 on specs/balanced_50.yaml (929 allocated crossers), 0.905 on specs/pedsynth_pp.yaml
/// (2,880); 98–99% of them step onto a driving lane, the rest cross unseen (after the ego passed, or too far).
pub const CROSSER_REALISATION: f64 = 0.90;
