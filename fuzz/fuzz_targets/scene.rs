//! Arbitrary bytes → TOML text → scene (parse, validate, parameters): a scene or an error on
//! one line; never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let text = String::from_utf8_lossy(bytes);
    match host_sim::scene::Scene::from_toml(&text) {
        Ok(scene) => {
            let _ = scene.params();
            let _ = scene.to_toml();
        }
        Err(e) => assert!(!format!("{e:#}").contains('\n')),
    }
});
