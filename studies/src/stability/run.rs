//! One case run: step by step with the energy, finiteness and failure checks.

use super::*;

/// Runs a case on the current thread (see [`run_case`] for the big-stack, panic-catching one).
pub fn run_case_here(case: &Case) -> Outcome {
    let t0 = Instant::now();
    let h = case.params.integrator.step;
    let steps_total = (case.duration / h).round() as usize;
    let mut out = Outcome {
        steps_total,
        finite: true,
        energy_checked: true,
        margin: f64::NEG_INFINITY,
        max_alpha: f64::NAN,
        ..Outcome::default()
    };
    let mut probe = match build(case, case.input.at(0, h)) {
        Ok(p) => p,
        Err(e) => {
            out.error = Some(format!("at rest: {e}"));
            out.margin = f64::NAN;
            out.seconds = t0.elapsed().as_secs_f64();
            return out;
        }
    };
    // A loaded run is checked only through a solver's `Balance` (every solver here has one).
    out.energy_checked = case.arm.is_none() || probe.balance().is_some();
    let ip = &case.params.integrator;
    // Newmark's algorithmic energy: E + ½(β − γ/2) h² aᵀ M a (≥ E since β ≥ γ/2), with a the
    // scheme's acceleration-like variable (generalized-α's; q̈ for Newmark). docs/model.md,
    // "Energy balance of a step".
    let c_alg = (ip.beta - 0.5 * ip.gamma) * h * h;
    let alpha_scheme = !ip.is_newmark();
    let e_alg = |pr: &dyn Probe| match (alpha_scheme, pr.balance()) {
        (true, Some(b)) => pr.energy() + c_alg * b.pseudo_accel_energy(),
        _ => pr.energy() + c_alg * pr.accel_energy(),
    };
    let e0 = e_alg(&*probe);
    // Work of the applied loads per step, Δqᵀ (w₀ F_n + w₁ F_{n+1}): the trapezoid for
    // generalized-α (whose filter term φ Δqᵀ M Δ(a − q̈), φ = ½ − α_f, is subtracted), the
    // weights (1 − γ, γ) for Newmark.
    let (w_old, w_new) = if alpha_scheme {
        (0.5, 0.5)
    } else {
        (1.0 - ip.gamma, ip.gamma)
    };
    let phi = 0.5 - ip.alpha_f;
    let mut held = match (&case.arm, probe.balance()) {
        (Some(_), Some(b)) => Some((
            b.load_vector(0.0, &vec![0.0; case.elements]),
            b.coordinates(),
            b.filter_lag(),
        )),
        _ => None,
    };
    out.floor = 64.0 * probe.epsilon() * probe.energy_magnitude();
    let static_tip = probe.static_tip();
    let (mut a_prev, mut p_prev) = (case.input.at(0, h), probe.momentum());
    let mut work = 0.0;
    let mut worst = f64::NEG_INFINITY;
    let mut worst_startup = f64::NEG_INFINITY;
    let mut scale = 0.0f64;
    let mut iters = 0u64;
    for k in 1..=steps_total {
        let a = case.input.at(k, h);
        let before = probe.bits().0;
        let mut sampled = None;
        let stepped = match &case.arm {
            Some(arm) => {
                let (tip, line) = arm.loads.sample(k as f64 * h, case.elements);
                let r = probe.step_loaded(a, tip, &line);
                sampled = Some((tip, line));
                r
            }
            None => probe.step(a),
        };
        match stepped {
            Ok(r) => {
                out.steps += 1;
                iters += u64::from(r.iterations);
                out.max_iterations = out.max_iterations.max(r.iterations);
                out.impacts += usize::from(r.impact.is_some());
            }
            Err(e) => {
                out.state_kept = Some(probe.bits().0 == before);
                out.error = Some(format!("step {k} (t = {:.4} s): {e}", k as f64 * h));
                break;
            }
        }
        let (_, finite) = probe.bits();
        if !finite {
            out.finite = false;
            out.error = Some(format!("step {k}: non-finite state accepted"));
            break;
        }
        out.max_tip = out.max_tip.max((probe.tip() - static_tip).abs());
        if !out.energy_checked {
            continue;
        }
        let p = probe.momentum();
        work -= 0.5 * h * (a_prev * p_prev + a * p);
        (a_prev, p_prev) = (a, p);
        if let (Some((f_old, q_old, lag_old)), Some(b), Some((tip, line))) =
            (held.as_mut(), probe.balance(), sampled.as_ref())
        {
            let (f_new, q_new, lag_new) =
                (b.load_vector(*tip, line), b.coordinates(), b.filter_lag());
            let dq: Vec<f64> = q_new.iter().zip(q_old.iter()).map(|(x, y)| x - y).collect();
            work += dq
                .iter()
                .zip(f_old.iter().zip(&f_new))
                .map(|(d, (f0, f1))| d * (w_old * f0 + w_new * f1))
                .sum::<f64>();
            if alpha_scheme {
                let dlag: Vec<f64> = lag_new
                    .iter()
                    .zip(lag_old.iter())
                    .map(|(x, y)| x - y)
                    .collect();
                work -= phi * b.mass_inner(&dq, &dlag);
            }
            (*f_old, *q_old, *lag_old) = (f_new, q_new, lag_new);
        }
        let de = e_alg(&*probe) - e0;
        if !de.is_finite() {
            out.finite = false;
        }
        let t = k as f64 * h;
        if t <= STARTUP + 0.5 * h {
            worst_startup = worst_startup.max(de - work);
        } else if de - work > worst {
            worst = de - work;
            out.excess_at = t;
        }
        scale = scale.max(de.abs()).max(work.abs());
        let al = probe.alpha().abs();
        if al.is_finite() {
            out.max_alpha = if out.max_alpha.is_nan() {
                al
            } else {
                out.max_alpha.max(al)
            };
        }
    }
    out.scale = scale;
    out.work = work;
    out.excess = worst;
    out.excess_startup = worst_startup;
    out.margin = if scale > 0.0 { worst / scale } else { 0.0 };
    out.margin_startup = if scale > 0.0 {
        worst_startup / scale
    } else {
        0.0
    };
    if !out.energy_checked {
        (out.margin, out.margin_startup, out.scale, out.floor) =
            (f64::NAN, f64::NAN, f64::NAN, f64::NAN);
    }
    out.mean_iterations = if out.steps > 0 {
        iters as f64 / out.steps as f64
    } else {
        0.0
    };
    out.seconds = t0.elapsed().as_secs_f64();
    out
}

/// Stack of the threads that run cases: the core with N = 64 (D = 257) keeps several 257×257
/// static matrices (0.5 MB each in f64) on the stack.
pub const STACK: usize = 512 << 20;

/// Runs a case in its own thread with a big stack; a panic is caught and reported.
pub fn run_case(case: &Case) -> Outcome {
    let c = case.clone();
    let r = std::thread::Builder::new()
        .stack_size(STACK)
        .spawn(move || run_case_here(&c))
        .map_err(|e| e.to_string())
        .and_then(|j| {
            j.join().map_err(|p| {
                p.downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| p.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown panic".into())
            })
        });
    r.unwrap_or_else(|msg| Outcome {
        panicked: true,
        error: Some(format!("PANIC: {msg}")),
        margin: f64::NAN,
        ..Outcome::default()
    })
}
