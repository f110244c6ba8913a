use super::*;
use crate::estimate::BaselineLoad;

/// The lab study refuses what it cannot run, naming the field: a scene without the free
/// ball, a run that ends before the first episode has ramped up, a bad baseline load model.
#[test]
fn lab_refuses_scenes_and_options_it_cannot_run() {
    let arm = Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/mast-arm.toml"
    ))
    .expect("scene");
    let e = lab(&arm, 10.0, 0.05, BaselineLoad::default()).expect_err("beam scene");
    assert!(e.to_string().contains("kind = \"free\""), "{e}");
    let e = lab(&Scene::paper(), 1.0, 0.05, BaselineLoad::default()).expect_err("too short");
    assert!(e.to_string().contains("`--duration`"), "{e}");
    let bad = BaselineLoad {
        step: Some(f64::NAN),
        time: 5.0,
    };
    let e = lab(&Scene::paper(), 10.0, 0.05, bad).expect_err("NaN load step");
    assert!(e.to_string().contains("`--load-step`"), "{e}");
}
