use absorber_core::{FreeBallModel, Params};
fn main() {
    let mut p = Params::<f64>::default();
    p.integrator.max_iterations = 100;
    if std::env::args().count() > 1 {
        p.integrator.newton = absorber_core::NewtonKind::Full;
    }
    let w = 2.0 * core::f64::consts::PI * 4.13;
    let u = |k: usize| -5e-3 * w * w * (w * k as f64 * 3e-3).sin();
    let mut a = FreeBallModel::<f64, 3, 13>::at_rest(p, u(0)).expect("start");
    for k in 1..=400 {
        let before = a.state().contact;
        let r = a.step(u(k)).unwrap();
        if r.iterations > 6 || (170..=185).contains(&k) {
            println!(
                "k={k} {:?}->{:?} it={} sep={:?} land={:?} imp={:?}",
                before,
                a.state().contact,
                r.iterations,
                r.separation,
                r.landing.map(|l| (l.bounced, l.normal_speed)),
                r.impact.map(|i| i.relative_speed)
            );
        }
    }
}
