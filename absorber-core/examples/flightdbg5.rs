use absorber_core::{FreeBallModel, Params};
fn main() {
    let p = Params::<f32>::default();
    let mut m: FreeBallModel<f32, 3, 13> = FreeBallModel::at_rest(p, 0.0).unwrap();
    let w = 2.0 * core::f32::consts::PI * 4.13;
    for k in 1..=6667u32 {
        let t = k as f32 * 0.003;
        let r = m.step(-0.5e-3 * w * w * libm::sinf(w * t)).unwrap();
        if r.separation.is_some() {
            println!("first separation at step {k}, t = {t}");
            break;
        }
    }
}
