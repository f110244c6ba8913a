//! The `f32` core beside the `f64` core over a long run.

use super::*;

/// The f32 core beside the f64 core over a long run: per window, the largest tip difference.
#[derive(Clone, Debug, PartialEq)]
pub struct DriftWindow {
    /// Window end \[s\].
    pub end: f64,
    /// max |tip_f32 − tip_f64| \[m\].
    pub tip_diff: f64,
    /// max |tip − static| of the f64 run \[m\] (for scale).
    pub tip_amplitude: f64,
    /// max |α_f32 − α_f64| \[rad\].
    pub alpha_diff: f64,
    /// max |α| of the f64 run \[rad\].
    pub alpha_amplitude: f64,
    /// The f32 model's clock minus k h at the window end \[s\].
    pub clock_f32: f64,
}

/// Runs the paper scene (free ball, N = 3) in `f32` and `f64` side by side at `frequency`,
/// 0.5 mm, for `duration` s, windows of `window` s.
pub fn drift(frequency: f64, duration: f64, window: f64) -> Result<Vec<DriftWindow>, Error> {
    use absorber_core::FreeBallModel;
    let p = Params::<f64>::default();
    let h = p.integrator.step;
    let input = harmonic(0.5e-3, frequency);
    let a0 = input.at(0, h);
    let mut m64: FreeBallModel<f64, 3, 13> = Model::at_rest(p, a0)?;
    let mut m32: FreeBallModel<f32, 3, 13> =
        Model::at_rest(absorber_sim::core_sim::params_f32(&p), a0 as f32)?;
    let (s64, s32) = (
        m64.static_tip_deflection(),
        f64::from(m32.static_tip_deflection()),
    );
    let steps = (duration / h).round() as usize;
    let per = ((window / h).round() as usize).max(1);
    let mut out = Vec::new();
    let mut w = DriftWindow {
        end: 0.0,
        tip_diff: 0.0,
        tip_amplitude: 0.0,
        alpha_diff: 0.0,
        alpha_amplitude: 0.0,
        clock_f32: 0.0,
    };
    for k in 1..=steps {
        let a = input.at(k, h);
        m64.step(a)?;
        m32.step(a as f32)?;
        let t64 = m64.tip_deflection() - s64;
        let t32 = f64::from(m32.tip_deflection()) - s32;
        let a64 = m64.ball_relative_angle().map_or(0.0, |x| x.0);
        let a32 = m32.ball_relative_angle().map_or(0.0, |x| f64::from(x.0));
        w.tip_diff = w.tip_diff.max((t32 - t64).abs());
        w.tip_amplitude = w.tip_amplitude.max(t64.abs());
        w.alpha_diff = w.alpha_diff.max((a32 - a64).abs());
        w.alpha_amplitude = w.alpha_amplitude.max(a64.abs());
        if k % per == 0 || k == steps {
            w.end = k as f64 * h;
            w.clock_f32 = f64::from(m32.time()) - k as f64 * h;
            out.push(w.clone());
            w = DriftWindow {
                end: 0.0,
                tip_diff: 0.0,
                tip_amplitude: 0.0,
                alpha_diff: 0.0,
                alpha_amplitude: 0.0,
                clock_f32: 0.0,
            };
        }
    }
    Ok(out)
}
