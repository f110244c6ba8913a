//! The embedded core behind [`Simulator`] for the accuracy candidates: `core_sim`'s model,
//! started with [`Start::BootConverged`] (a fixed Newton budget cannot run the static solve of
//! `at_rest`, so such a model boots with the converged solver).

use super::Body;
use absorber_core::{Error, Params};
use absorber_full::sim::Simulator;
use absorber_sim::core_sim::{build_from, Start};
use absorber_sim::scene::{Kind, Precision};

/// The embedded core for `body` with `n` elements in `f32` or `f64`, at rest with input `a0`.
pub fn build_embedded(
    body: Body,
    n: usize,
    f32: bool,
    params: &Params<f64>,
    a0: f64,
) -> Result<Box<dyn Simulator>, Error> {
    let kind = match body {
        Body::Free => Kind::Free,
        Body::Locked => Kind::Locked,
    };
    let precision = if f32 { Precision::F32 } else { Precision::F64 };
    build_from(kind, n, precision, params, a0, Start::BootConverged)
}
