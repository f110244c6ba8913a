//! The document's figures: the sweep (Fig. 10), the time histories at 4.13 Hz (Figs. 16, 19,
//! 20) and the ball at 4.25 Hz (Figs. 22–23).

use super::claims::{Histories, Study, Sweeps};
use super::signal::{amplitude_blocks, running_mean};
use absorber_sim::figures::ENERGY_MEAN_WINDOW;
use absorber_sim::output::OutputDir;
use absorber_sim::plot::{render, Panel, Series};
use absorber_sim::run::Row;
use absorber_sim::sweep::SweepPoint;
use anyhow::Result;

/// Palette index of each scene, the same on every panel: free ball with Table 1 (N = 3), with
/// Table 1 on the converged mesh, with the tuned R, locked ball.
const TABLE1: usize = 0;
const TUNED: usize = 2;
const LOCKED: usize = 3;

/// Draws the three figures into `out`.
pub(super) fn draw(out: &mut OutputDir, study: &Study) -> Result<()> {
    let Sweeps {
        table1,
        table1_conv,
        tuned: tuned_pts,
        locked: locked_pts,
        ..
    } = &study.sweeps;
    let Histories {
        locked413,
        free413,
        tuned413,
        free425,
    } = &study.histories;
    let converged = study.converged;
    let pts = |p: &[SweepPoint], f: fn(&SweepPoint) -> f64| {
        p.iter()
            .filter(|q| !q.failed())
            .map(|q| (q.frequency, f(q)))
            .collect::<Vec<_>>()
    };
    let failed_at: Vec<f64> = [&table1, &table1_conv, &tuned_pts, &locked_pts]
        .iter()
        .flat_map(|p| p.iter().filter(|q| q.failed()).map(|q| q.frequency))
        .collect();
    let tip_mm = |q: &SweepPoint| q.tip_amplitude * 1e3;
    let ball_deg = |q: &SweepPoint| q.ball_amplitude_deg;
    out.write_with("validation-sweep.png", |p| {
        render(
            p,
            "Frequency response, 0.5 mm base amplitude (paper Fig. 10)",
            &[
                Panel::new(
                    "tip amplitude",
                    "base frequency [Hz]",
                    "tip amplitude [mm]",
                    vec![
                        Series::marked("free ball, Table 1, N = 3", pts(table1, tip_mm)),
                        Series::marked(
                            &format!("free ball, Table 1, N = {converged}"),
                            pts(table1_conv, tip_mm),
                        ),
                        Series::marked("free ball, tuned R, N = 3", pts(tuned_pts, tip_mm)),
                        Series::marked("locked ball, N = 3", pts(locked_pts, tip_mm)),
                    ],
                )
                .with_failed(failed_at.clone()),
                Panel::new(
                    "ball amplitude",
                    "base frequency [Hz]",
                    "ball angle amplitude [deg]",
                    vec![
                        Series::marked("free ball, Table 1, N = 3", pts(table1, ball_deg)),
                        Series::marked(
                            &format!("free ball, Table 1, N = {converged}"),
                            pts(table1_conv, ball_deg),
                        ),
                        Series::marked("free ball, tuned R, N = 3", pts(tuned_pts, ball_deg)),
                    ],
                )
                .with_failed(failed_at.clone()),
            ],
            1,
            2,
            (1400, 560),
        )
    })?;
    let series = |rows: &[Row], f: fn(&Row) -> f64| {
        rows.iter()
            .step_by(4)
            .map(|r| (r.t, f(r)))
            .collect::<Vec<_>>()
    };
    // Only where the kernel (half-width one window) lies inside the run, as in `run`'s plot.
    let mean = |pts: Vec<(f64, f64)>| {
        let (a, b) = (
            pts.first().map_or(0.0, |p| p.0),
            pts.last().map_or(0.0, |p| p.0),
        );
        running_mean(&running_mean(&pts, ENERGY_MEAN_WINDOW), ENERGY_MEAN_WINDOW)
            .into_iter()
            .filter(|p| p.0 >= a + ENERGY_MEAN_WINDOW && p.0 <= b - ENERGY_MEAN_WINDOW)
            .collect::<Vec<_>>()
    };
    out.write_with("validation-4p13.png", |p| render(
        p,
        "4.13 Hz, N = 3: locked ball, free ball with Table 1's R and with the tuned R (paper Figs. 16, 19, 20)",
        &[
            Panel::new(
                "tip amplitude: half peak-to-peak of the tip deflection over 1 s blocks",
                "t [s]",
                "amplitude [mm]",
                vec![
                    Series::line("locked ball", amplitude_blocks(locked413, 1.0)).colored(LOCKED).width(2),
                    Series::line("free ball, Table 1", amplitude_blocks(free413, 1.0)).colored(TABLE1).width(2),
                    Series::line("free ball, tuned R", amplitude_blocks(tuned413, 1.0)).colored(TUNED).width(2),
                ],
            ),
            Panel::new(
                "ball angle relative to the housing",
                "t [s]",
                "α [deg]",
                vec![
                    Series::line("free ball, Table 1", series(free413, |r| r.ball_rel_angle.to_degrees())).colored(TABLE1),
                    Series::line("free ball, tuned R", series(tuned413, |r| r.ball_rel_angle.to_degrees())).colored(TUNED),
                ],
            ),
            Panel::new(
                &format!("kinetic energies, {w} s running mean applied twice (the beam → ball transfer)", w = ENERGY_MEAN_WINDOW),
                "t [s]",
                "energy [mJ]",
                vec![
                    Series::line("beam, Table 1", mean(series(free413, |r| r.energies.beam_kinetic * 1e3))).colored(TABLE1).width(2),
                    Series::line("ball, Table 1", mean(series(free413, |r| r.energies.ball_kinetic * 1e3))).colored(TABLE1).dashed().width(2),
                    Series::line("beam, tuned R", mean(series(tuned413, |r| r.energies.beam_kinetic * 1e3))).colored(TUNED).width(2),
                    Series::line("ball, tuned R", mean(series(tuned413, |r| r.energies.ball_kinetic * 1e3))).colored(TUNED).dashed().width(2),
                ],
            ),
        ],
        3,
        1,
        (1200, 1100),
    ))?;
    out.write_with("validation-4p25.png", |p| {
        render(
            p,
            "4.25 Hz, N = 3: ball angle of the ensemble's run 0 (paper Figs. 22–23)",
            &[Panel::new(
                "ball angle relative to the housing",
                "t [s]",
                "α [deg]",
                vec![Series::line(
                    "free ball",
                    series(free425, |r| r.ball_rel_angle.to_degrees()),
                )],
            )],
            1,
            1,
            (1200, 420),
        )
    })?;
    Ok(())
}
