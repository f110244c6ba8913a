use absorber_core::{FreeBallModel, Params};
fn main() {
    let p = Params::<f32>::default();
    let mut m = FreeBallModel::<f32, 3, 13>::at_rest(p, 0.0).unwrap();
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        seed ^= seed >> 12;
        seed ^= seed << 25;
        seed ^= seed >> 27;
        let u = (seed.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32;
        (2.0 * u - 1.0) * 5.0 * 9.81
    };
    let mut fl = 0u64;
    for k in 0..342_398u64 {
        let a = next();
        let before = *m.state();
        match m.step(a) {
            Ok(r) => {
                fl += m.in_flight() as u64;
                if k >= 342385 {
                    let s = m.state();
                    let (c, _) = m.ball_centre().unwrap();
                    let ax = m.params().beam.length + s.q[8];
                    let ay = s.q[9];
                    let rr = ((c[0] - ax).powi(2) + (c[1] - ay).powi(2)).sqrt();
                    print!("r={rr:.4} ");
                    println!("k={k} {:?} it={} sep={:?} land={:?} imp={:?} v_end={:?} a_end={:?} ball={:?}", s.contact, r.iterations, r.separation, r.landing.map(|l| (l.bounced, l.normal_speed, l.normal_impulse, l.tangential_impulse)), r.impact.map(|i| i.relative_speed), &s.v.as_slice()[8..13], &s.a.as_slice()[8..13], m.ball_centre());
                }
            }
            Err(e) => {
                println!(
                    "k={k} {e:?} contact={:?} flight={:?}",
                    before.contact, before.flight
                );
                m.restart(a).unwrap();
            }
        }
    }
    println!("flight fraction {}", fl as f64 / 1e6);
}
