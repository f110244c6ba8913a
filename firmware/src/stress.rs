//! The stress set: inputs that try to break the work bound of a firmware bin (`docs/embedded.md`,
//! "Stress set"). Each scene is chosen on the command line (`stress=<name>`, host and target
//! alike) and replaces the paper's input, and for some the ball's restitution or the start, for
//! a few thousand steps. The inputs are computed in `f32` with `libm` and a fixed-seed integer
//! generator, so the host and the Cortex-M4F see the same samples bit for bit.
//!
//! | scene | input |
//! |---|---|
//! | `resonance_2x`, `_10x`, `_40x` | the paper's sine at 2, 10 and 40 times its amplitude (1, 5, 20 mm) |
//! | `glitch_8g`, `_16g`, `_full` | the paper's input, each sample replaced with probability 0.01 by ±8 g, ±16 g, or a value uniform over the whole input range ±1e4 m/s² |
//! | `shock` | the paper's input plus a 30 ms half-sine shock of 500 m/s² at t = 5 s |
//! | `noise` | uniform noise over the whole input range ±1e4 m/s², every sample |
//! | `spun` | the paper's input from a start with the ball thrown along the track at 50 rad/s |
//! | `plastic`, `elastic` | ten times the paper's amplitude with restitution 0 or 1 (stops and landings) |

use crate::AMPLITUDE;

/// Standard gravity \[m/s²\] (the glitch levels are in g).
const G: f32 = 9.806_65;
/// The model's input range ±`MAX_BASE_ACCEL` in `f32` \[m/s²\].
const FULL_RANGE: f32 = 1.0e4;

/// What a stress scene does to the paper's run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input {
    /// The paper's sine at `factor` times its amplitude.
    Resonance(f32),
    /// The paper's input; with probability `1/100` per sample a glitch: `±level` \[m/s²\], or
    /// (`level` = 0) a value uniform over the whole input range.
    Glitch(f32),
    /// The paper's input plus a half-sine shock of `peak` \[m/s²\] lasting `ms` from t = 5 s.
    Shock { peak: f32, ms: u32 },
    /// Uniform noise over the whole input range, every sample.
    Noise,
}

/// A stress scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stress {
    /// Name on the command line (`stress=<name>`) and in `docs/embedded.json` (`stress_<name>`).
    pub name: &'static str,
    /// Steps run.
    pub steps: u32,
    /// The input.
    pub input: Input,
    /// Restitution of the stops and of landings, if changed.
    pub restitution: Option<f32>,
    /// The ball thrown along the track at this relative angular speed at the start \[rad/s\].
    pub spin: Option<f32>,
}

const fn scene(name: &'static str, steps: u32, input: Input) -> Stress {
    Stress {
        name,
        steps,
        input,
        restitution: None,
        spin: None,
    }
}

/// Every stress scene.
pub const SCENES: [Stress; 12] = [
    scene("resonance_2x", 3000, Input::Resonance(2.0)),
    scene("resonance_10x", 3000, Input::Resonance(10.0)),
    scene("resonance_40x", 3000, Input::Resonance(40.0)),
    scene("glitch_8g", 3000, Input::Glitch(8.0 * G)),
    scene("glitch_16g", 3000, Input::Glitch(16.0 * G)),
    scene("glitch_full", 3000, Input::Glitch(0.0)),
    scene(
        "shock",
        2000,
        Input::Shock {
            peak: 500.0,
            ms: 30,
        },
    ),
    scene("noise", 2000, Input::Noise),
    Stress {
        spin: Some(50.0),
        ..scene("spun", 2000, Input::Resonance(1.0))
    },
    Stress {
        restitution: Some(0.0),
        ..scene("plastic", 3000, Input::Resonance(10.0))
    },
    Stress {
        restitution: Some(1.0),
        ..scene("elastic", 3000, Input::Resonance(10.0))
    },
    // A single full-range sample in the paper's run (t = 5 s): the recovery after one bad
    // sample, on its own.
    scene(
        "one_glitch",
        2000,
        Input::Shock {
            peak: -9059.0,
            ms: 0,
        },
    ),
];

/// The scene called `name`.
pub fn find(name: &str) -> Option<&'static Stress> {
    SCENES.iter().find(|s| s.name == name)
}

/// A fixed-seed xorshift32 generator: the same sequence on every target.
#[derive(Clone, Copy, Debug)]
pub struct Rng(u32);

impl Default for Rng {
    fn default() -> Self {
        Rng(0x9e37_79b9)
    }
}

impl Rng {
    /// The next 32 random bits.
    pub fn bits(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }

    /// Uniform in \[−1, 1) from 24 bits (exact in `f32`).
    pub fn symmetric(&mut self) -> f32 {
        ((self.bits() >> 8) as f32) / 8_388_608.0 - 1.0
    }
}

impl Stress {
    /// The base acceleration of step `k` (time `k h`) \[m/s²\]; `sine(factor)` is the paper's
    /// input at the bin's frequency times `factor`, `rng` the scene's generator.
    pub fn accel(&self, k: u32, h: f32, frequency: f32, rng: &mut Rng) -> f32 {
        let paper = |factor: f32| factor * crate::base_accel(k, h, frequency);
        match self.input {
            Input::Resonance(factor) => paper(factor),
            Input::Glitch(level) => {
                let draw = rng.bits();
                let sign = rng.symmetric();
                // 1 in 100: the top 32 bits below 2³² / 100.
                if draw < u32::MAX / 100 {
                    if level == 0.0 {
                        FULL_RANGE * sign
                    } else if sign < 0.0 {
                        -level
                    } else {
                        level
                    }
                } else {
                    paper(1.0)
                }
            }
            Input::Shock { peak, ms } => {
                let start = 5000 / crate::STEP_MS;
                let len = ms / crate::STEP_MS;
                let shock = if k == start && len == 0 {
                    peak
                } else if k >= start && k < start + len {
                    let x = (k - start) as f32 / len as f32;
                    peak * libm::sinf(core::f32::consts::PI * (x + 0.5 / len as f32))
                } else {
                    0.0
                };
                paper(1.0) + shock
            }
            Input::Noise => FULL_RANGE * rng.symmetric(),
        }
    }
}

/// What a run was asked for on the command line.
#[derive(Clone, Copy, Debug, Default)]
pub struct Setup {
    /// The stress scene, if any (else the paper's run).
    pub stress: Option<&'static Stress>,
}

impl Setup {
    /// Takes `stress=<name>`; `Err` with the argument if the name is not a scene.
    pub fn arg<'a>(&mut self, a: &'a str) -> Result<(), &'a str> {
        if let Some(name) = a.strip_prefix("stress=") {
            self.stress = Some(find(name).ok_or(a)?);
        }
        Ok(())
    }

    /// Steps of the run.
    pub fn steps(&self) -> u32 {
        self.stress.map_or(crate::STEPS, |s| s.steps)
    }

    /// The paper's amplitude times the scene's factor, as printed \[m\].
    pub fn amplitude(&self) -> f32 {
        match self.stress.map(|s| s.input) {
            Some(Input::Resonance(f)) => f * AMPLITUDE,
            _ => AMPLITUDE,
        }
    }
}
