//! The study's test scenes: bodies, inputs (harmonic, noise) and the paper's noise.

use serde::{Deserialize, Serialize};

/// The bodies of a test scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Body {
    /// Free ball between the stops.
    Free,
    /// Ball locked in the housing.
    Locked,
}

/// Sum of sines: band-limited, deterministic, defined at every time (so runs with different
/// steps see the same signal).
#[derive(Clone, Debug, PartialEq)]
pub struct Noise {
    /// (amplitude \[m/s²\], ω \[rad/s\], phase \[rad\]).
    pub parts: Vec<(f64, f64, f64)>,
}

impl Noise {
    /// `count` components spread evenly (jittered) over `[f_lo, f_hi]` Hz, random phases from
    /// `seed` ([`absorber_sim::wind::Rng`]), equal amplitudes giving the RMS `rms` \[m/s²\].
    pub fn new(seed: u64, count: usize, f_lo: f64, f_hi: f64, rms: f64) -> Self {
        let mut rng = absorber_sim::wind::seeded(seed);
        let mut uniform = move || rand::RngExt::random::<f64>(&mut rng);
        let amp = rms * (2.0 / count as f64).sqrt();
        let parts = (0..count)
            .map(|i| {
                let f = f_lo + (f_hi - f_lo) * (i as f64 + uniform()) / count as f64;
                (
                    amp,
                    std::f64::consts::TAU * f,
                    std::f64::consts::TAU * uniform(),
                )
            })
            .collect();
        Self { parts }
    }

    /// ÿ_b(t).
    pub fn accel(&self, t: f64) -> f64 {
        self.parts
            .iter()
            .map(|&(a, w, p)| a * (w * t + p).sin())
            .sum()
    }
}

/// Base input of a test scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// y_b = A sin(2π f t).
    Harmonic {
        /// A \[m\].
        amplitude: f64,
        /// f \[Hz\].
        frequency: f64,
    },
    /// Band-limited noise acceleration.
    Random(Noise),
}

impl Input {
    /// ÿ_b(t) \[m/s²\].
    pub fn accel(&self, t: f64) -> f64 {
        match self {
            Input::Harmonic {
                amplitude,
                frequency,
            } => {
                let w = std::f64::consts::TAU * frequency;
                -amplitude * w * w * (w * t).sin()
            }
            Input::Random(n) => n.accel(t),
        }
    }
}

/// A fixed scene of the report.
#[derive(Clone, Debug, PartialEq)]
pub struct TestScene {
    /// Short name (file names, tables).
    pub name: &'static str,
    /// Description.
    pub title: &'static str,
    /// Bodies.
    pub body: Body,
    /// Base input.
    pub input: Input,
}

/// The noise of the random scenes: 200 sines over 1–10 Hz, RMS 1 m/s², seed 4.
pub fn paper_noise() -> Noise {
    Noise::new(4, 200, 1.0, 10.0, 1.0)
}

pub(super) fn harmonic(f: f64) -> Input {
    Input::Harmonic {
        amplitude: 0.5e-3,
        frequency: f,
    }
}

/// The report's scenes.
pub fn scenes() -> Vec<TestScene> {
    vec![
        TestScene {
            name: "free-3.70",
            title: "free ball, 3.70 Hz",
            body: Body::Free,
            input: harmonic(3.70),
        },
        TestScene {
            name: "free-4.13",
            title: "free ball, 4.13 Hz (paper)",
            body: Body::Free,
            input: harmonic(4.13),
        },
        TestScene {
            name: "free-4.25",
            title: "free ball, 4.25 Hz",
            body: Body::Free,
            input: harmonic(4.25),
        },
        TestScene {
            name: "locked-4.13",
            title: "locked ball, 4.13 Hz",
            body: Body::Locked,
            input: harmonic(4.13),
        },
        TestScene {
            name: "locked-noise",
            title: "locked ball, noise 1–10 Hz, 1 m/s² RMS",
            body: Body::Locked,
            input: Input::Random(paper_noise()),
        },
        TestScene {
            name: "free-noise",
            title: "free ball, noise 1–10 Hz, 1 m/s² RMS",
            body: Body::Free,
            input: Input::Random(paper_noise()),
        },
    ]
}
