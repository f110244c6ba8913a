use absorber_core::*;
fn run(e: f64, im: ImpactModel) {
    let mut p = Params::<f64>::default();
    p.ball.restitution = e; p.ball.impact_model = im;
    p.integrator.gamma = 0.5; p.integrator.beta = 0.25; p.integrator.step = 0.001;
    p.ball.initial_angle = -62f64.to_radians();
    let mut m: Model<f64, FreeBall, 3, 13> = Model::at_rest(p, 0.0).unwrap();
    let e0 = m.energies(0.0,0.0).total();
    let mut worst: f64 = 0.0; let mut n = 0; let mut sumk = 0.0;
    for _ in 1..=5000 {
        let before = m.energies(0.0,0.0).total();
        let r = match m.step(0.0) { Ok(r) => r, Err(e) => { println!("fail {e}"); break; } };
        let after = m.energies(0.0,0.0).total();
        if let Some(i) = r.impact { n += 1; let k = 0.5*0.014*1.4*0.032f64.powi(2)*i.relative_speed.powi(2); sumk += k; worst = worst.max(((after-before) + i.energy_loss).abs()/k); }
    }
    println!("{im:?} e={e}: impacts {n}, drift {:.3e} J of {e0:.3e}; worst per-impact energy error / ball KE {worst:.3e}; mean ball KE {:.2e}", m.energies(0.0,0.0).total()-e0, sumk/(n as f64));
}
fn main() {
    for im in [ImpactModel::Instantaneous, ImpactModel::OverStep] { run(1.0, im); run(0.5, im); }
}
