//! Arbitrary bytes → TOML text → scene (parse, validate, parameters): a scene or an error on
//! one line; never a panic. Scenes with an `[arm]` also build the arm's parameters (validated
//! against the beam) and, with `[[loads]]`, the load model, sampled at a few times: finite.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let text = String::from_utf8_lossy(bytes);
    match absorber_sim::scene::Scene::from_toml(&text) {
        Ok(scene) => {
            let p = scene.params().expect("a validated scene has parameters");
            let _ = scene.to_toml();
            let f = &scene.file;
            if let Some(arm) = &f.arm {
                let ap = arm.params().expect("a validated arm has parameters");
                assert!(ap.validate(&p.beam).is_ok());
                if !f.loads.is_empty() {
                    let taper = absorber_sim::scene::taper_of(arm, f.beam.length);
                    let loads = absorber_sim::wind::LoadModel::new(&f.loads, taper, &scene.base_dir)
                        .expect("validated loads build");
                    for t in [0.0, f.integrator.step, 0.5 * f.duration] {
                        let (tip, line) = loads.sample(t, f.elements);
                        assert!(
                            tip.is_finite() && line.iter().all(|x| x.is_finite()),
                            "t = {t}"
                        );
                    }
                }
            }
        }
        Err(e) => assert!(!format!("{e:#}").contains('\n')),
    }
});
