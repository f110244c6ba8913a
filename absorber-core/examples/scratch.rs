use absorber_core::*;
fn main() {
    let p = Params::<f64>::default();
    let m: LockedBallModel<f64, 3, 12> = Model::at_rest(p, 0.0).unwrap();
    println!("static locked N3: {:.6} mm", m.static_tip_deflection() * 1e3);
    println!("freqs: {:?}", &m.natural_frequencies().unwrap().as_slice()[..4]);
    let m: LockedBallModel<f64, 16, 64> = Model::at_rest(p, 0.0).unwrap();
    println!("static locked N16: {:.6} mm", m.static_tip_deflection() * 1e3);
    println!("freqs: {:?}", &m.natural_frequencies().unwrap().as_slice()[..4]);
    let mut m: FreeBallModel<f64, 3, 13> = Model::at_rest(p, 0.0).unwrap();
    println!("free freqs: {:?}", &m.natural_frequencies().unwrap().as_slice()[..4]);
    let w = 2.0 * std::f64::consts::PI * 4.13;
    let mut maxit = 0; let mut nimp = 0; let mut maxa: f64 = 0.0;
    for k in 1..=20000 {
        let t = k as f64 * 0.003;
        let r = m.step(-0.5e-3 * w * w * (w * t).sin()).unwrap();
        maxit = maxit.max(r.iterations);
        if r.impact.is_some() { nimp += 1; }
        let a = m.ball_relative_angle().unwrap().0; maxa = maxa.max(a.abs());
        if k % 1000 == 0 { println!("t={t:.1} y={:.3}mm alpha={:.1}deg maxit={maxit} impacts={nimp} E={:.3e}", m.tip_deflection()*1e3, a.to_degrees(), m.energies(0.0,0.0).total()); }
    }
}
