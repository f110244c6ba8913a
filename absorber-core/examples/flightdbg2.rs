use absorber_core::{FreeBallModel, Params};
fn main() {
    let mut p = Params::<f64>::default();
    p.beam.modulus *= 1e4;
    p.integrator.gamma = 0.5;
    p.integrator.beta = 0.25;
    p.integrator.step = 1e-3;
    let mut heavier = p;
    heavier.gravity *= 1.001;
    let start = FreeBallModel::<f64, 3, 13>::at_rest(heavier, 0.0).unwrap();
    let mut m = FreeBallModel::<f64, 3, 13>::at_rest(p, 0.0).unwrap();
    m.set_configuration(start.state().q, start.state().v, 0.0)
        .unwrap();
    let mut minn = f64::MAX;
    for k in 0..4000 {
        let r = m.step(0.0).unwrap();
        let n = m.contact_forces().unwrap().normal;
        minn = minn.min(n);
        if k % 100 == 0 || (k > 1855 && k < 1864) {
            let st = m.state();
            println!(
                "k={k} N={n:.4e} ay={:.3e} ax={:.3e} aslope={:.3e} {:.3e}",
                st.a[9], st.a[8], st.a[10], st.a[11]
            );
            println!(
                "k={k} N={n:.4e} sep={:?} land={:?} a={:?}",
                r.separation,
                r.landing,
                m.ball_relative_angle()
            );
        }
    }
    println!("min N {minn:e} (m_b g = {})", 0.014 * 9.81);
}
