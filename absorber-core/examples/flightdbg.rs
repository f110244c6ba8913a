use absorber_core::{FreeBallModel, Params};
use core::f64::consts::PI;
fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let (amp, f) = (args[0], args[1]);
    let p = Params::<f64>::default();
    let h = p.integrator.step;
    let omega = 2.0 * PI * f;
    let accel = |t: f64| -amp * omega * omega * (omega * t).sin();
    let mut m: FreeBallModel<f64, 3, 13> = FreeBallModel::at_rest(p, 0.0).expect("valid");
    let (mut sep, mut land, mut bounce, mut imp, mut fl, mut its, mut maxit) =
        (0, 0, 0, 0, 0, 0u64, 0);
    for k in 1..=20000u64 {
        match m.step(accel(k as f64 * h)) {
            Ok(r) => {
                sep += r.separation.is_some() as u32;
                if let Some(l) = r.landing {
                    land += 1;
                    bounce += l.bounced as u32;
                }
                imp += r.impact.is_some() as u32;
                fl += m.in_flight() as u32;
                its += r.iterations as u64;
                maxit = maxit.max(r.iterations);
            }
            Err(e) => {
                println!("k={k} error {e:?}");
                break;
            }
        }
    }
    println!("sep {sep} land {land} bounce {bounce} impacts {imp} flight steps {fl} ({:.1} %) mean it {:.2} max it {maxit} t={}", fl as f64 / 200.0, its as f64/20000.0, m.time());
}
