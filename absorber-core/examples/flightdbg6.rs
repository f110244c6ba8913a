use absorber_core::{FreeBallModel, Params};
fn main() {
    let p = Params::<f64>::default();
    let (amp, f, h) = (50e-3, 4.13, 3e-3);
    let w = 2.0 * std::f64::consts::PI * f;
    let u = |k: usize| -amp * w * w * (w * k as f64 * h).sin();
    let mut m = FreeBallModel::<f64, 3, 13>::at_rest(p, u(0)).unwrap();
    for k in 1..=520usize {
        let before = *m.state();
        match m.step(u(k)) {
            Ok(r) => {
                if k >= 495 {
                    let s = m.state();
                    println!(
                        "k={k} {:?} it={} sep={:?} land={:?} imp={:?} v_end={:?} ball={:?}",
                        s.contact,
                        r.iterations,
                        r.separation,
                        r.landing.map(|l| (l.bounced, l.normal_speed)),
                        r.impact.map(|i| i.relative_speed),
                        &s.v.as_slice()[8..13]
                            .iter()
                            .map(|x| (x * 100.0).round() / 100.0)
                            .collect::<Vec<_>>(),
                        m.ball_centre().map(|(c, v)| (
                            (c[0] * 1e4).round() / 1e4,
                            (c[1] * 1e4).round() / 1e4,
                            (v[0] * 100.0).round() / 100.0,
                            (v[1] * 100.0).round() / 100.0
                        ))
                    );
                }
            }
            Err(e) => {
                println!("k={k} {e:?} contact={:?}", before.contact);
                break;
            }
        }
    }
}
