use super::*;
use crate::kin::{Mode, PHI};
use crate::sim::Simulator;
use crate::SceneKind;
use absorber_core::ImpactModel;
use absorber_core::Params;

/// (a) The first test, as the core's (`absorber-core/tests/flight.rs`): a stiff beam
/// (E × 10⁴, first mode ≈ 400 Hz) makes the housing follow the base, which accelerates
/// down at 1.5 g from rest. The ball leaves the track in the step where the rolling
/// model's normal force first turns negative (the same run with `ball.flight = false`,
/// bit-identical until then), and from the first state in flight it follows the closed-form
/// ballistic path relative to the base, `c(t) = c₁ + ċ₁ (t − t₁) − ½ g_eff (t − t₁)² ŷ`, until
/// it lands. Reference: the closed form; budget: Newmark (any γ, β) is exact for a constant
/// acceleration, so only rounding remains: 1e-12 m (positions, and velocities times h).
#[test]
fn ball_separates_where_n_turns_negative_and_flies_ballistically_until_it_lands() {
    let mut p = Params::<f64>::default();
    p.beam.modulus *= 1e4;
    let h = p.integrator.step;
    let u = -1.5 * p.gravity;
    let g_eff = p.gravity + u;
    let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
    let mut held_p = p;
    held_p.ball.flight = false;
    let mut held = FullSolver::at_rest(held_p, SceneKind::FreeBall, 3, 0.0).expect("start");
    let mut first = None;
    for k in 1..=100 {
        let r = s.step(u).expect("step");
        held.step(u).expect("step");
        let pulls = held.contact_forces().expect("ball").0 < 0.0;
        if r.separation.is_some() {
            assert!(pulls, "step {k}: separated where the track still pushes");
            first = Some(k);
            break;
        }
        assert!(!pulls, "step {k}: the track pulls and the ball stays");
        assert_eq!(s.state, held.state, "step {k}: rolling, bit-identical");
    }
    let k1 = first.expect("the ball leaves the track");
    assert!(s.in_flight());
    let t1 = s.state.time;
    let (c1, v1) = s.ball_centre().expect("ball");
    let spin = s.state.v[s.zloc(PHI)];
    let (mut worst, mut landed) = (0.0f64, None);
    for _ in 0..400 {
        let r = s.step(u).expect("step");
        if let Some(l) = r.landing {
            landed = Some(l);
            break;
        }
        assert!(s.in_flight());
        assert_eq!(s.contact_forces(), Some((0.0, 0.0)));
        let t = s.state.time - t1;
        let (c, v) = s.ball_centre().expect("ball");
        let exact = [c1[0] + v1[0] * t, c1[1] + v1[1] * t - 0.5 * g_eff * t * t];
        worst = worst
            .max((c[0] - exact[0]).abs())
            .max((c[1] - exact[1]).abs())
            .max((v[0] - v1[0]).abs() * h)
            .max((v[1] - (v1[1] - g_eff * t)).abs() * h);
        assert_eq!(s.state.v[s.zloc(PHI)], spin, "no torque on the spin");
    }
    let l = landed.expect("the ball lands on the top of the track");
    println!(
        "separated in step {k1} (t = {t1:.4} s), landed at {:.4} s (v_n = {:.3} m/s, \
         bounced: {}); worst ballistic error {worst:.2e} m",
        l.time, l.normal_speed, l.bounced
    );
    // It falls up across the housing, about 2ρ = 64 mm at 0.5 g: ≈ 0.16 s.
    assert!((0.08..0.3).contains(&(l.time - t1)), "{}", l.time - t1);
    assert!(worst < 1e-12, "{worst:e}");
}

/// (b) Elastic landings and stops, as the core's test: e_n = e = 1, frictionless bounces,
/// the instantaneous impulse (mass metric: ½(1 − e²) v_n²/K = 0), the trapezoidal rule
/// (γ = ½, β = ¼, h = 0.1 ms) and a constant effective gravity (−0.5 g: the ball falls
/// across the housing and bounces), 1 s. Reference: the initial energy in the base frame.
/// Budget: the core's, 1 % of the ball's drop energy m_b g_eff 2ρ — each instantaneous
/// bounce kicks the housing's stiff end-rotation mode, whose energy the trapezoidal rule
/// keeps only to O((ωh)²) in the nonlinear beam — and it must exceed the potential energy
/// moved by the radial projections onto the circle, `m_b |g_eff| Σ|r − ρ|` (printed).
#[test]
fn elastic_landings_conserve_energy() {
    let mut p = Params::<f64> {
        gravity: -0.5 * 9.81,
        ..Default::default()
    };
    p.integrator.gamma = 0.5;
    p.integrator.beta = 0.25;
    p.integrator.step = 1e-4;
    p.ball.landing_restitution = 1.0;
    p.ball.restitution = 1.0;
    p.ball.stick_speed = 0.0;
    p.ball.impact_model = ImpactModel::Instantaneous;
    let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
    let energy = |s: &FullSolver| s.energies(0.0, 0.0).total();
    let e0 = energy(&s);
    let scale = p.ball.mass * 0.5 * 9.81 * 2.0 * p.ball.path_radius();
    let (mut worst, mut projection, mut landings) = (0.0f64, 0.0f64, 0);
    for _ in 0..10_000 {
        let r = s.step(0.0).expect("step");
        if let Some(l) = r.landing {
            assert!(l.bounced, "elastic landings bounce");
            landings += 1;
            projection += s.work.borrow_mut().projection;
        }
        worst = worst.max((energy(&s) - e0).abs());
    }
    let moved = p.ball.mass * p.gravity.abs() * projection;
    println!(
        "{landings} bounces in 1 s: worst |ΔE| = {worst:.2e} J = {:.2e} of m_b g 2ρ; \
         projections Σ|r − ρ| = {projection:.2e} m ({:.2e} of m_b g 2ρ)",
        worst / scale,
        moved / scale
    );
    assert!(landings >= 2, "{landings}");
    assert!(moved < 1e-2 * scale);
    assert!(worst < 1e-2 * scale, "{:e}", worst / scale);
}

/// (c) Small amplitudes: the paper scene at 3.5 Hz, 0.2 mm, 2 s keeps N > 0 throughout, and
/// the runs with flight on and off are bit-identical (reference: the run without flight;
/// budget: zero).
#[test]
fn small_amplitudes_are_bit_identical_with_and_without_flight() {
    let mut p = Params::<f64>::default();
    let mut on = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
    p.ball.flight = false;
    let mut off = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
    let h = p.integrator.step;
    let w = 2.0 * core::f64::consts::PI * 3.5;
    let mut n_min = f64::INFINITY;
    for k in 1..=(2.0 / h) as usize {
        let u = -0.2e-3 * w * w * (w * k as f64 * h).sin();
        let (ra, rb) = (on.step(u).expect("on"), off.step(u).expect("off"));
        assert_eq!(ra, rb);
        assert_eq!(on.state, off.state, "step {k}");
        n_min = n_min.min(on.contact_forces().expect("ball").0);
    }
    println!("3.5 Hz, 0.2 mm: min N = {n_min:.4e} N");
    assert!(n_min > 0.0);
}

/// (d) The plastic landing's momentum projection of a ball already on the circle, moving
/// tangentially without slip and with zero normal speed (a rolling state relabelled as in
/// flight) changes nothing: positions and velocities to rounding (1e-12 relative).
#[test]
fn plastic_landing_of_a_rolling_ball_changes_nothing() {
    let mut p = Params::<f64>::default();
    p.ball.initial_angle = 30f64.to_radians();
    let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
    for _ in 0..40 {
        s.step(0.0).expect("step");
    }
    let rolling = s.state.clone();
    assert_eq!(rolling.contact, Contact::Off);
    let mut f = rolling.clone();
    f.contact = Contact::InFlight;
    let rel = s.relative(&f);
    let n = [rel.d[0] / rel.r, rel.d[1] / rel.r];
    let (i1, i2) = (s.zloc(RB1), s.zloc(RB2));
    let before = [f.v[i1], f.v[i2]];
    let vt = (rel.rate[0].powi(2) + rel.rate[1].powi(2)).sqrt();
    assert!(vt > 0.05, "rolls: {vt} m/s");
    let (p_n, p_t) = s.roll_on(&mut f, n, before).expect("projection");
    let scale = |x: &[f64]| x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let dq = rolling
        .q
        .iter()
        .zip(f.q.iter())
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let dv = rolling
        .v
        .iter()
        .zip(f.v.iter())
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    println!(
        "plastic projection of a rolling ball: |Δq| = {dq:.2e}, |Δv| = {dv:.2e}, \
         P = ({p_n:.2e}, {p_t:.2e}) N·s"
    );
    assert_eq!(f.contact, Contact::Off);
    assert!(dq <= 1e-12 * scale(&rolling.q), "{dq:e}");
    assert!(dv <= 1e-12 * scale(&rolling.v), "{dv:e}");
}

/// The generalized momentum of the rolling coordinates, `Bᵀ M v` (B the rolling mode's
/// velocity transformation at `s`'s configuration, M the constant mass matrix, `v` any
/// velocity over the maximal coordinates).
fn rolling_momentum(solver: &FullSolver, s: &FullState, v: &[f64]) -> Vec<f64> {
    let n = solver.n;
    let mut mv = vec![0.0; solver.nz];
    for e in 0..n {
        for i in 0..8 {
            mv[4 * e + i] += (0..8)
                .map(|j| solver.me[(i, j)] * v[4 * e + j])
                .sum::<f64>();
        }
    }
    for jb in 0..solver.n_body {
        mv[solver.b0() + jb] += solver.bodies.mass[4 + jb] * v[solver.b0() + jb];
    }
    let mode = Mode::Free;
    let loc0 = 4 * n - 4;
    let qi = solver.gather_ind(&s.q, mode);
    let vi = solver.gather_ind(&s.v, mode);
    let kin = solver
        .local_kin(
            mode,
            &qi[loc0..],
            &vi[loc0..],
            &solver.local_of(&s.q),
            s.theta_ref,
        )
        .expect("kinematics");
    let mut p: Vec<f64> = (0..qi.len()).map(|i| mv[solver.ind_to_z(i)]).collect();
    for (k, pk) in p[loc0..].iter_mut().enumerate() {
        for (r, &j) in mode.dependent().iter().enumerate() {
            *pk += kin.bd[r][k] * mv[solver.zloc(j)];
        }
    }
    p
}

/// (d′) The plastic landing is the momentum projection `v_r⁺ = (Bᵀ M B)⁻¹ Bᵀ M v⁻` (mass
/// metric, `impact_model = Instantaneous`): a ball on the circle moving in and slipping
/// (0.02 m/s outwards, 0.05 m/s along the track relative to rolling) rolls on afterwards —
/// no normal speed, the rolling kinematics — and `Bᵀ M v` is unchanged (reference: before
/// the landing; budget 1e-10 of its largest entry, rounding of the sparse solves).
#[test]
fn plastic_landing_keeps_the_rolling_momentum() {
    let mut p = Params::<f64>::default();
    p.ball.initial_angle = 30f64.to_radians();
    p.ball.impact_model = ImpactModel::Instantaneous;
    let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
    for _ in 0..40 {
        s.step(0.0).expect("step");
    }
    let mut f = s.state.clone();
    f.contact = Contact::InFlight;
    let rel = s.relative(&f);
    let n = [rel.d[0] / rel.r, rel.d[1] / rel.r];
    let (i1, i2) = (s.zloc(RB1), s.zloc(RB2));
    f.v[i1] += 0.02 * n[0] - 0.05 * n[1];
    f.v[i2] += 0.02 * n[1] + 0.05 * n[0];
    let before_v = f.v.clone();
    let centre_rate = [f.v[i1], f.v[i2]];
    let (p_n, p_t) = s.roll_on(&mut f, n, centre_rate).expect("projection");
    let before = rolling_momentum(&s, &f, &before_v);
    let after = rolling_momentum(&s, &f, &f.v);
    let big = before.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = before
        .iter()
        .zip(after.iter())
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let rel = s.relative(&f);
    let vn = rel.radial_rate();
    println!(
        "plastic landing with slip: |Δ(Bᵀ M v)| = {diff:.2e} of {big:.2e}; normal speed \
         after {vn:.2e} m/s; P = ({p_n:.3e}, {p_t:.3e}) N·s"
    );
    assert!(diff <= 1e-10 * big, "{diff:e}");
    assert!(vn.abs() < 1e-12, "{vn:e}");
    assert!(p_n > 0.0, "the track pushes: {p_n:e}");
}

/// (e) A flying ball that hits a stop from the arc beyond it (the core's test of the same
/// name): at the stops' height on a housing at rest, e = 0.5 and 0.9, h = 3 ms, the ball 0.5°
/// beyond the stop at 0.5 m/s towards it. One impact, after which it flies away from the stop
/// on the side it came from, no faster than its rebound, e × 0.5 m/s plus what gravity adds
/// before the crossing (g sin 65° × 3 ms = 0.027 m/s at most). Counted between the stops after
/// its impulse, it got a second impulse from the stop's track face at the end of the step (two
/// impacts) that sent it back through the stop at 0.097 m/s.
#[test]
fn a_stop_hit_from_beyond_in_flight_is_one_impact_and_the_ball_stays_beyond() {
    for e in [0.5, 0.9] {
        let mut p = Params::<f64>::default();
        p.ball.restitution = e;
        p.ball.landing_restitution = e;
        let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
        let mut f = s.state.clone();
        let (a, _) = s.end_point(&f);
        let psi = f.q[s.zloc(crate::kin::PSI)];
        let stop = p.ball.stop_angle;
        let (r, v0) = (0.030, 0.5);
        let th = psi + stop + 0.5f64.to_radians();
        let (i1, i2) = (s.zloc(RB1), s.zloc(RB2));
        f.contact = Contact::InFlight;
        f.theta_ref = th;
        f.beyond = true;
        f.q[i1] = a[0] + r * th.sin();
        f.q[i2] = a[1] - r * th.cos();
        // Along the track towards the stop (θ decreasing).
        f.v[i1] = -v0 * th.cos();
        f.v[i2] = -v0 * th.sin();
        let g = s.effective_gravity(0.0);
        for (z, acc) in [(i1, 0.0), (i2, -g)] {
            f.a[z] = acc;
            f.pa[z] = acc;
        }
        s.state = f;
        let (alpha0, rate0) = (s.relative_angle(&s.state), s.relative_rate(&s.state));
        assert!(alpha0 > stop && rate0 < 0.0, "{alpha0} {rate0}");
        let report = s.step(0.0).expect("step");
        let (alpha1, rate1) = (s.relative_angle(&s.state), s.relative_rate(&s.state));
        let speed = rate1 * s.relative(&s.state).r;
        println!(
            "e = {e}: impacts {}, α − α_max {:.3e} rad, speed {speed:.4} m/s",
            report.events.impacts,
            alpha1 - stop
        );
        assert_eq!(report.events.impacts, 1);
        assert_eq!(s.state.contact, Contact::InFlight);
        assert!(alpha1 > stop, "{alpha1} ≤ {stop}");
        assert!(
            speed > 0.0 && speed <= e * v0 + 0.03,
            "{speed} against e v0 = {}",
            e * v0
        );
    }
}

/// (f) A ball dropped onto the arc beyond the positive stop (the core's test of the same
/// name: at rest 1 mm inside the circle, 15° beyond the stop, on a housing at rest; h = 3 ms,
/// e = e_n = 0.5, 30 s) lands, rolls down into the stop's other face, bounces off it and comes
/// to rest against it: a few impacts, none in the second half, the ball held on the stop from
/// beyond. Statics by hand: α = α_max, and the stop's face carries the ball's weight along the
/// track, `E_θ = m_b ρ g sin(ψ + α_max)` (ψ the housing's tilt), pushing the ball beyond the
/// stop; budget 1e-3, the housing's ringing from the impacts (the core's). Before, a ball
/// pressed onto the other face went through it within the step, onto the track's side.
#[test]
fn a_ball_on_the_arc_beyond_a_stop_comes_to_rest_against_its_other_face() {
    let p = Params::<f64>::default();
    let mut s = FullSolver::at_rest(p, SceneKind::FreeBall, 3, 0.0).expect("start");
    let mut f = s.state.clone();
    let (a, _) = s.end_point(&f);
    let psi = f.q[s.zloc(crate::kin::PSI)];
    let stop = p.ball.stop_angle;
    let r = p.ball.path_radius() - 1e-3;
    let th = psi + stop + 15f64.to_radians();
    let (i1, i2) = (s.zloc(RB1), s.zloc(RB2));
    f.contact = Contact::InFlight;
    f.theta_ref = th;
    f.beyond = true;
    f.q[i1] = a[0] + r * th.sin();
    f.q[i2] = a[1] - r * th.cos();
    let g = s.effective_gravity(0.0);
    for (z, acc) in [(i1, 0.0), (i2, -g)] {
        f.v[z] = 0.0;
        f.a[z] = acc;
        f.pa[z] = acc;
    }
    s.state = f;
    let steps = (30.0 / p.integrator.step).round() as usize;
    let (mut impacts, mut late) = (0u32, 0u32);
    for k in 0..steps {
        let report = s.step(0.0).expect("step");
        impacts += u32::from(report.events.impacts);
        if k >= steps / 2 {
            late += u32::from(report.events.impacts);
        }
    }
    let st = s.state.clone();
    let alpha = s.relative_angle(&st);
    let psi = st.q[s.zloc(crate::kin::PSI)];
    let force = s.contact_force(&st).expect("force");
    let statics = p.ball.mass * p.ball.path_radius() * g * (psi + stop).sin();
    println!(
        "impacts {impacts} (last 2 s: {late}), contact {:?} beyond {}, α − α_max {:.1e}, \
         E_θ {force:.6e} against m ρ g sin θ {statics:.6e} ({:.1e})",
        st.contact,
        st.beyond,
        alpha - stop,
        (force - statics) / statics
    );
    assert_eq!(st.contact, Contact::OnStop(Side::Positive));
    assert!(st.beyond);
    assert_eq!(late, 0);
    assert!(impacts <= 20, "{impacts}");
    assert!((alpha - stop).abs() < 1e-12, "{alpha}");
    assert!(statics > 0.0 && (force - statics).abs() < 1e-3 * statics);
}
