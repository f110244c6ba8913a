//! The paper's figures from a run: time histories, FFT, phase planes, energy curves.

use crate::fft::spectrum;
use crate::plot::{render, Panel, Series};
use crate::run::Row;
use crate::scene::Plot;
use anyhow::Result;
use std::path::{Path, PathBuf};

/// Largest number of points drawn per curve (longer runs are thinned).
const MAX_POINTS: usize = 20_000;

fn thin(rows: &[Row]) -> impl Iterator<Item = &Row> {
    let every = rows.len().div_ceil(MAX_POINTS).max(1);
    rows.iter().step_by(every)
}

fn series(rows: &[Row], label: &str, f: impl Fn(&Row) -> (f64, f64)) -> Series {
    Series::line(label, thin(rows).map(f).collect())
}

/// FFT of `x` over rows with t ≥ `from`, up to `max_hz`.
pub fn fft_points(
    rows: &[Row],
    from: f64,
    max_hz: f64,
    x: impl Fn(&Row) -> f64,
) -> Vec<(f64, f64)> {
    let tail: Vec<&Row> = rows.iter().filter(|r| r.t >= from).collect();
    if tail.len() < 4 {
        return Vec::new();
    }
    let dt = (tail[tail.len() - 1].t - tail[0].t) / (tail.len() - 1) as f64;
    let s = spectrum(&tail.iter().map(|r| x(r)).collect::<Vec<_>>(), dt);
    s.frequency
        .iter()
        .zip(&s.amplitude)
        .filter(|(f, _)| **f <= max_hz)
        .map(|(f, a)| (*f, *a))
        .collect()
}

/// Writes the requested plots of a run into `dir` as `<stem>_<plot>.png`; returns the paths.
pub fn run_plots(
    dir: &Path,
    stem: &str,
    title: &str,
    rows: &[Row],
    plots: &[Plot],
    transient: f64,
) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let has_ball = rows.iter().any(|r| r.ball_angle.is_finite());
    let deg = f64::to_degrees;
    for plot in plots {
        let (name, panels, rows_cols, size) = match plot {
            Plot::Time => {
                let mut p = vec![Panel::new(
                    "Beam tip",
                    "t [s]",
                    "y [m]",
                    vec![
                        series(rows, "deflection (relative)", |r| (r.t, r.tip_deflection)),
                        series(rows, "base y_b", |r| (r.t, r.base_y)),
                    ],
                )];
                if has_ball {
                    p.push(Panel::new(
                        "Ball",
                        "t [s]",
                        "angle [deg]",
                        vec![
                            series(rows, "θ (from vertical)", |r| (r.t, deg(r.ball_angle))),
                            series(rows, "θ − ψ (in housing)", |r| {
                                (r.t, deg(r.ball_rel_angle))
                            }),
                        ],
                    ));
                } else {
                    p.push(Panel::new(
                        "Tip mass",
                        "t [s]",
                        "ψ [deg]",
                        vec![series(rows, "", |r| (r.t, deg(r.tip_angle)))],
                    ));
                }
                ("time", p, (2, 1), (1200, 800))
            }
            Plot::Fft => {
                let t = format!("after t = {transient} s");
                let mut p = vec![Panel::new(
                    &format!("FFT of the beam tip deflection ({t})"),
                    "f [Hz]",
                    "amplitude [m]",
                    vec![Series::line(
                        "",
                        fft_points(rows, transient, 10.0, |r| r.tip_deflection),
                    )],
                )];
                if has_ball {
                    p.push(Panel::new(
                        &format!("FFT of the ball angle θ ({t})"),
                        "f [Hz]",
                        "amplitude [deg]",
                        vec![Series::line(
                            "",
                            fft_points(rows, transient, 10.0, |r| deg(r.ball_angle)),
                        )],
                    ));
                }
                ("fft", p, (p_len(has_ball), 1), (1200, 800))
            }
            Plot::Phase => {
                let mut p = vec![Panel::new(
                    "Beam tip y – ẏ",
                    "y [m]",
                    "ẏ [m/s]",
                    vec![series(rows, "", |r| (r.tip_deflection, r.tip_velocity))],
                )];
                if has_ball {
                    p.push(Panel::new(
                        "Ball θ – θ̇",
                        "θ [rad]",
                        "θ̇ [rad/s]",
                        vec![series(rows, "", |r| (r.ball_angle, r.ball_rate))],
                    ));
                    p.push(Panel::new(
                        "Ball spin φ – φ̇",
                        "φ [rad]",
                        "φ̇ [rad/s]",
                        vec![series(rows, "", |r| (r.ball_spin, r.ball_spin_rate))],
                    ));
                    p.push(Panel::new(
                        "Ball θ – tip mass ψ",
                        "ψ [rad]",
                        "θ [rad]",
                        vec![series(rows, "", |r| (r.tip_angle, r.ball_angle))],
                    ));
                    ("phase", p, (2, 2), (1200, 1000))
                } else {
                    p.push(Panel::new(
                        "Tip mass ψ – ψ̇",
                        "ψ [rad]",
                        "ψ̇ [rad/s]",
                        vec![series(rows, "", |r| (r.tip_angle, r.tip_rate))],
                    ));
                    ("phase", p, (1, 2), (1200, 550))
                }
            }
            Plot::Energy => {
                let mj = 1e3;
                let mut p = vec![
                    Panel::new(
                        "Beam energies",
                        "t [s]",
                        "E [mJ = N·mm]",
                        vec![
                            series(rows, "strain", |r| (r.t, mj * r.energies.beam_strain)),
                            series(rows, "kinetic", |r| (r.t, mj * r.energies.beam_kinetic)),
                            series(rows, "potential Δ", |r| {
                                (r.t, mj * r.energies.beam_potential)
                            }),
                        ],
                    ),
                    Panel::new(
                        "Tip mass energies",
                        "t [s]",
                        "E [mJ]",
                        vec![
                            series(rows, "kinetic", |r| (r.t, mj * r.energies.tip_kinetic)),
                            series(rows, "potential Δ", |r| {
                                (r.t, mj * r.energies.tip_potential)
                            }),
                        ],
                    ),
                ];
                if has_ball {
                    p.push(Panel::new(
                        "Ball energies",
                        "t [s]",
                        "E [mJ]",
                        vec![
                            series(rows, "kinetic", |r| (r.t, mj * r.energies.ball_kinetic)),
                            series(rows, "potential Δ", |r| {
                                (r.t, mj * r.energies.ball_potential)
                            }),
                        ],
                    ));
                    p.push(Panel::new(
                        "Kinetic energy: beam vs ball",
                        "t [s]",
                        "E [mJ]",
                        vec![
                            series(rows, "beam", |r| (r.t, mj * r.energies.beam_kinetic)),
                            series(rows, "ball", |r| (r.t, mj * r.energies.ball_kinetic)),
                        ],
                    ));
                }
                ("energy", p, (2, 2), (1200, 900))
            }
        };
        let path = dir.join(format!("{stem}_{name}.png"));
        render(&path, title, &panels, rows_cols.0, rows_cols.1, size)?;
        out.push(path);
    }
    Ok(out)
}

fn p_len(has_ball: bool) -> usize {
    if has_ball {
        2
    } else {
        1
    }
}
