use super::kin::Mode;
use super::*;
use absorber_core::shared::Chain;

/// The residual from the augmented system equals the beam residual plus the reduced local
/// residual (two routes to the same virtual work), and the Newton matrix is its derivative.
#[test]
fn residual_routes_agree_and_newton_matrix_is_derivative() {
    let mut s = FullSolver::new(Params::default(), SceneKind::FreeBall, 2).expect("valid");
    s.solve_static().expect("static");
    newton_matrix_is_derivative(&s, Mode::Free);
    // In flight: the ball's rows are its mass, the rest as on the track.
    newton_matrix_is_derivative(&s, Mode::Flying);
    // Resting on a stop (φ dependent, θ − ψ = α_lock).
    newton_matrix_is_derivative(&s, Mode::Held(0.6));
    let mut t = FullSolver::new(Params::default(), SceneKind::TipMass, 2).expect("valid");
    t.solve_static().expect("static");
    newton_matrix_is_derivative(&t, Mode::Tip);
}

/// The tip/ball block from the core's tip rows is the derivative of this solver's own local
/// residual (central differences, relative error of order 1e-9 from truncation and
/// rounding), in every mode it is used for, at a moving state far from rest and with the
/// chains of a step and of a static solve.
#[test]
fn tip_block_is_derivative_of_the_local_residual() {
    let mut s = FullSolver::new(Params::default(), SceneKind::FreeBall, 3).expect("valid");
    s.solve_static().expect("static");
    let mut t = FullSolver::new(Params::default(), SceneKind::TipMass, 3).expect("valid");
    t.solve_static().expect("static");
    let chains = [
        Chain {
            c_q: 0.36 * 9e-6,
            c_v: 0.7 * 3e-3,
            c_m: 1.0,
        },
        Chain {
            c_q: 1.0,
            c_v: 0.0,
            c_m: 0.0,
        },
    ];
    let cases = [
        (&s, Mode::Free),
        (&s, Mode::Flying),
        (&s, Mode::Held(-0.6)),
        (&t, Mode::Tip),
    ];
    for (solver, mode) in cases {
        for ch in &chains {
            let nl = mode.independent().len();
            let loc0 = 4 * solver.n - 4;
            let mut ql: Vec<f64> = solver.gather_ind(&solver.equilibrium.q, mode)[loc0..].to_vec();
            let (mut vl, mut al) = (vec![0.0; nl], vec![0.0; nl]);
            for i in 0..nl {
                let f = (i as f64 + 1.0) * 0.61;
                ql[i] += 0.05 * f.sin();
                vl[i] = 0.8 * (1.3 * f).cos();
                al[i] = 40.0 * (0.7 * f).sin();
            }
            let warm = solver.local_of(&solver.equilibrium.q);
            let kin = solver
                .local_kin(mode, &ql, &vl, &warm, 0.0)
                .expect("kinematics");
            let exact = solver
                .tip_block(mode, &ql, &vl, &al, ch, 9.3)
                .expect("a core ball mode");
            let fd = solver
                .tip_block_differences(&kin, mode, &ql, &vl, &al, ch, 9.3, 0.0)
                .expect("differences");
            let scale = exact.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            let coupled = if mode == Mode::Flying { 4 } else { nl };
            for i in 0..coupled {
                for j in 0..coupled {
                    assert!(
                        (exact[i][j] - fd[i][j]).abs() <= 1e-8 * scale,
                        "{mode:?} {ch:?}: [{i}][{j}] {} vs {}",
                        exact[i][j],
                        fd[i][j]
                    );
                }
            }
            // Outside the coupled block the core's rows put nothing the solver uses.
            assert!(scale > 0.0);
        }
    }
}

/// The block LU and the kept sparse LU (the reference) solve the real Newton and mass
/// matrices of a locked and a free step alike, to rounding, without the block LU's
/// fallback; and whole runs with either agree to rounding.
#[test]
fn block_and_sparse_lu_agree_on_real_steps() {
    let accel = |k: usize| {
        let w = 2.0 * core::f64::consts::PI * 3.70;
        -0.5e-3 * w * w * (w * k as f64 * 0.003).sin()
    };
    let cases = [
        (SceneKind::LockedBall, 16, 200),
        (SceneKind::FreeBall, 16, 200),
        // Short elements: a stiffness-dominated matrix, multipliers ~1/l across blocks.
        (SceneKind::LockedBall, 512, 20),
    ];
    for (scene, n, steps) in cases {
        let mut s = FullSolver::at_rest(Params::default(), scene, n, 0.0).expect("scene");
        let mut r = s.clone();
        r.set_linear(Linear::Sparse).expect("reference");
        for k in 1..=steps {
            s.step(accel(k)).expect("step");
            r.step(accel(k)).expect("reference step");
        }
        // Rounding at N = 16 (measured ≤ 2e-12 after 200 steps). At N = 512 each solve
        // agrees only to κ·ε ≈ 4e11 · 1.1e-16 ≈ 4e-5 of the correction (below), so a step's
        // positions to c_q·4e-5·|x| ≈ 3.2e-6 · 4e-5 · 50 m/s² ≈ 7e-9 m: 1.4e-7 over the
        // 20 steps (measured 1e-10).
        let run_agree = if n <= 16 { 1e-10 } else { 1.4e-7 };
        for (a, b) in s.state.q.iter().zip(r.state.q.iter()) {
            assert!(
                (a - b).abs() <= run_agree * (1.0 + b.abs()),
                "{scene:?} {n}: {a} vs {b}"
            );
        }
        // The Newton matrix of the next step at the current state.
        let mode = s.mode(s.state.contact);
        let ni = s.n_ind(mode);
        let qi = s.gather_ind(&s.state.q, mode);
        let vi = s.gather_ind(&s.state.v, mode);
        let ai = s.gather_ind(&s.state.a, mode);
        let ch = s.step_chain(s.params.integrator.step);
        let mut warm = s.local_of(&s.state.q);
        let mut guard = s.work.borrow_mut();
        let Work { mass, reduced, .. } = &mut *guard;
        let lu = s.reduced_lu(reduced, ni).expect("pattern");
        let ev = s
            .evaluate(
                mass,
                Some((&mut *lu, &ch)),
                &qi,
                &vi,
                &ai,
                9.81,
                mode,
                &mut warm,
                s.state.theta_ref,
            )
            .expect("eval");
        let mut reference = lu.with_linear(Linear::Sparse);
        assert!(lu.factor() && reference.factor());
        assert_eq!(lu.fallbacks(), 0, "{scene:?} {n}");
        assert_eq!(mass.lu.fallbacks(), 0, "{scene:?} {n}");
        let mut mass_ref = mass.lu.with_linear(Linear::Sparse);
        assert!(mass_ref.factor());
        let rhs: [Vec<f64>; 2] = [
            ev.r.clone(),
            (0..ni).map(|i| (0.7 * i as f64).sin()).collect(),
        ];
        // Both solves are backward stable (normwise backward error at rounding); at N = 16
        // they agree to 1e-12 relative, at N = 512 (condition ≈ 4e11) to what the condition
        // allows.
        let dense = lu.to_dense();
        for b in rhs {
            let (mut x, mut y) = (b.clone(), b.clone());
            assert!(lu.solve(&mut x) && reference.solve(&mut y));
            let bv = nalgebra::DVector::from_column_slice(&b);
            for z in [&x, &y] {
                let zv = nalgebra::DVector::from_column_slice(z);
                let eta = (&dense * &zv - &bv).amax() / (dense.amax() * zv.amax() + bv.amax());
                assert!(eta <= 1e-15, "{scene:?} {n}: backward error {eta:e}");
            }
            let big = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let agree = if n <= 16 { 1e-12 } else { 1e-3 };
            for (xa, ya) in x.iter().zip(y.iter()) {
                assert!(
                    (xa - ya).abs() <= agree * big,
                    "{scene:?} {n}: {xa} vs {ya}"
                );
            }
        }
        let nf = mass.f.len();
        let b: Vec<f64> = (0..nf).map(|i| (0.3 * i as f64).cos()).collect();
        let (mut x, mut y) = (b.clone(), b);
        assert!(mass.lu.solve(&mut x) && mass_ref.solve(&mut y));
        let big = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (xa, ya) in x.iter().zip(y.iter()) {
            assert!(
                (xa - ya).abs() <= 1e-12 * big,
                "{scene:?} mass: {xa} vs {ya}"
            );
        }
    }
}

fn newton_matrix_is_derivative(s: &FullSolver, mode: Mode) {
    let ni = s.n_ind(mode);
    let mut qi = s.gather_ind(&s.equilibrium.q, mode);
    let mut vi = vec![0.0; ni];
    let mut ai = vec![0.0; ni];
    for i in 0..ni {
        let f = (i as f64 + 1.0) * 0.37;
        qi[i] += 1e-3 * f.sin();
        vi[i] = 0.3 * (1.3 * f).cos();
        ai[i] = 20.0 * (0.7 * f).sin();
    }
    vi[ni - 1] = -30.0;
    let ch = Chain {
        c_q: 0.36 * 9e-6,
        c_v: 0.7 * 3e-3,
        c_m: 1.0,
    };
    let mut warm = s.local_of(&s.equilibrium.q);
    let mut guard = s.work.borrow_mut();
    let Work { mass, reduced, .. } = &mut *guard;
    let lu = s.reduced_lu(reduced, ni).expect("pattern");
    assert_eq!(lu.n(), ni);
    s.evaluate(
        mass,
        Some((&mut *lu, &ch)),
        &qi,
        &vi,
        &ai,
        9.0,
        mode,
        &mut warm,
        0.0,
    )
    .expect("eval");
    let jac = lu.to_dense();
    let scale = jac.amax();
    for j in 0..ni {
        let h = 1e-2;
        let mut pert = |sg: f64| {
            let q: Vec<f64> = (0..ni)
                .map(|i| qi[i] + if i == j { sg * h * ch.c_q } else { 0.0 })
                .collect();
            let v: Vec<f64> = (0..ni)
                .map(|i| vi[i] + if i == j { sg * h * ch.c_v } else { 0.0 })
                .collect();
            let a: Vec<f64> = (0..ni)
                .map(|i| ai[i] + if i == j { sg * h * ch.c_m } else { 0.0 })
                .collect();
            let mut w = warm;
            s.evaluate(mass, None, &q, &v, &a, 9.0, mode, &mut w, 0.0)
                .expect("eval")
                .r
        };
        let (rp, rm) = (pert(1.0), pert(-1.0));
        for i in 0..ni {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            assert!(
                (fd - jac[(i, j)]).abs() <= 1e-6 * scale,
                "J[{i},{j}] {} vs fd {fd}",
                jac[(i, j)]
            );
        }
    }
}
