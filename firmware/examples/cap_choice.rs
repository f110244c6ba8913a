//! What a bin's work cap costs on the paper's input: the firmware's model of a bin run on the
//! host (the same `f32` code the firmware runs) without a cap and with each cap given, side by
//! side over the paper's 20 s: the capped steps, the most units a step took, and how far the
//! capped run is from the uncapped one (tip and ball RMS, and the largest tip difference)
//! (`docs/embedded.md`, "Firmware defaults": the caps of N = 6, modified Newton and the ball
//! held on the track).
//!
//! Usage: `cargo run --release -p absorber-firmware --example cap_choice -- <bin> <cap>…`
//! with `<bin>` one of `free`, `free-rolling`, `free-modified`, `free-n6`.

use absorber_core::work;
use absorber_core::{Error, FreeBall, FreeBallNoFlight, Model, NewtonKind, Outcome, Scene};
use absorber_firmware::{base_accel, firmware_params, Setup, FREQUENCY_HZ, STEPS};

/// One run: tip deflection (dynamic part) \[mm\] and ball angle \[deg\] after every step, the
/// most units of a step, capped steps, restarts and failed steps.
struct Run {
    tip: Vec<f64>,
    ball: Vec<f64>,
    max_work: u32,
    capped: u32,
    restarts: u32,
    failed: u32,
}

fn run<S: Scene, const N: usize, const D: usize>(cap: u32, modified: bool) -> Result<Run, Error> {
    let mut p = firmware_params(&Setup::default());
    if modified {
        p.integrator.newton = NewtonKind::Modified;
    }
    p.integrator.max_work = cap;
    let mut m = Model::<f32, S, N, D>::at_rest(p, 0.0)?;
    let h = m.params().integrator.step;
    let mut r = Run {
        tip: Vec::with_capacity(STEPS as usize),
        ball: Vec::with_capacity(STEPS as usize),
        max_work: 0,
        capped: 0,
        restarts: 0,
        failed: 0,
    };
    for k in 1..=STEPS {
        match m.step(base_accel(k, h, FREQUENCY_HZ)) {
            Ok(rep) => {
                r.max_work = r.max_work.max(u32::from(rep.work));
                match rep.outcome {
                    Outcome::Capped => r.capped += 1,
                    Outcome::Restarted => r.restarts += 1,
                    Outcome::Converged => {}
                }
            }
            Err(_) => r.failed += 1,
        }
        r.tip
            .push(f64::from(m.tip_deflection() - m.static_tip_deflection()) * 1e3);
        r.ball
            .push(f64::from(m.ball_relative_angle().map_or(0.0, |a| a.0)).to_degrees());
    }
    Ok(r)
}

fn rms(x: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0.0);
    for v in x {
        s += v * v;
        n += 1.0;
    }
    (s / n).sqrt()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let bin = args.first().map(String::as_str).unwrap_or("");
    let caps: Result<Vec<u32>, _> = args.iter().skip(1).map(|s| s.parse::<u32>()).collect();
    let Ok(caps) = caps else {
        eprintln!("usage: cap_choice <free|free-rolling|free-modified|free-n6> <cap>…");
        std::process::exit(2);
    };
    let go = |cap: u32| match bin {
        "free" => run::<FreeBall, 3, 13>(cap, false),
        "free-rolling" => run::<FreeBallNoFlight, 3, 13>(cap, false),
        "free-modified" => run::<FreeBall, 3, 13>(cap, true),
        "free-n6" => run::<FreeBall, 6, 25>(cap, false),
        _ => {
            eprintln!("unknown bin {bin:?} (free, free-rolling, free-modified, free-n6)");
            std::process::exit(2);
        }
    };
    let base = match go(work::UNLIMITED) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{bin}: the uncapped run did not start: {e:?}");
            std::process::exit(1);
        }
    };
    let (tip0, ball0) = (
        rms(base.tip.iter().copied()),
        rms(base.ball.iter().copied()),
    );
    let peak = base.tip.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    println!(
        "{bin}, paper input, no cap: most units in a step {}, error steps {}, tip RMS {tip0:.4} mm, θ RMS {ball0:.3}°",
        base.max_work,
        base.capped + base.restarts + base.failed
    );
    println!("| cap | most units | capped / restarts / failed | tip RMS [mm] (change) | θ RMS [°] (change) | RMS of the tip difference [% of tip RMS] | largest tip difference [% of peak] |");
    println!("|---:|---:|---|---|---|---:|---:|");
    for cap in caps {
        let r = match go(cap) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("{bin}: cap {cap}: did not start: {e:?}");
                std::process::exit(1);
            }
        };
        let (tip, ball) = (rms(r.tip.iter().copied()), rms(r.ball.iter().copied()));
        let diff = || r.tip.iter().zip(&base.tip).map(|(a, b)| a - b);
        let largest = diff().fold(0.0f64, |a, v| a.max(v.abs()));
        println!(
            "| {cap} | {} | {} / {} / {} | {tip:.4} ({:+.3} %) | {ball:.3} ({:+.3} %) | {:.3} | {:.3} |",
            r.max_work,
            r.capped,
            r.restarts,
            r.failed,
            100.0 * (tip / tip0 - 1.0),
            100.0 * (ball / ball0 - 1.0),
            100.0 * rms(diff()) / tip0,
            100.0 * largest / peak
        );
    }
}
