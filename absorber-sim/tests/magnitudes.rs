//! Extreme magnitudes in a scene are refused when the scene is read, by the key, its value and
//! the allowed range (derived in `Scene::check_magnitudes`: ratios that meet in one entry of the
//! f64 mass or stiffness matrix within 1/ε, lengths within 1/√ε, a ball's inertia at most
//! m·r²). Before, each of these ended in "cannot start: … singular" naming no key.

use absorber_sim::scene::Scene;

fn refused(toml: &str, words: &[&str]) {
    let e = match Scene::from_toml(toml) {
        Ok(_) => panic!("accepted: {toml}"),
        Err(e) => format!("{e:#}"),
    };
    for w in words {
        assert!(e.contains(w), "`{w}` not in: {e}");
    }
    assert!(e.contains("allowed"), "no range in: {e}");
    assert!(!e.contains("singular system"), "{e}");
}

#[test]
fn extreme_magnitudes_name_the_key_value_and_range() {
    // Beam mass against the end masses (tip 0.1154 + ball 0.014 kg): at least ε × them.
    refused(
        "[beam]\nmass = 1e-300\n",
        &["`beam.mass`", "1e-300", "`tip.mass`"],
    );
    refused("[beam]\nmass = 1e300\n", &["`beam.mass`", "1e300"]);
    // Axial against bending stiffness: a·L² / I within [ε, 1/ε].
    refused("[beam]\narea = 1e300\n", &["`beam.area`", "1e300"]);
    refused(
        "[beam]\ninertia = 1e-290\nmodulus = 1e290\n",
        &["`beam.inertia`"],
    );
    // Lengths against the beam length, within 1/√ε = 6.7e7.
    refused(
        "[tip]\noffset = 1e300\n",
        &["`tip.offset`", "1e300", "0.000e0 ..= 2.4"],
    );
    refused(
        "[ball]\ntrack_radius = 1e300\n",
        &["`ball.track_radius`", "1e300"],
    );
    refused("[tip]\ninertia = 1e300\n", &["`tip.inertia`", "1e300"]);
    refused("[tip]\nmass = 1e300\n", &["`tip.mass`", "1e300"]);
    // A ball's inertia about its centre is at most m·r² (paper: 0.014 kg, 7.5 mm: 7.875e-7).
    refused(
        "[ball]\ninertia = 1e300\n",
        &["`ball.inertia`", "1e300", "7.8750e-7"],
    );
    refused(
        "[ball]\ninertia = 8e-7\n",
        &["`ball.inertia`", "8e-7", "7.8750e-7"],
    );
    // The radius is the key far from its value: named, with the smallest radius the inertia
    // allows, √(3.15e-7 / 0.014) = 4.743e-3 m.
    refused(
        "[ball]\nradius = 1e-300\n",
        &["`ball.radius`", "1e-300", "4.7434e-3"],
    );
    refused("[ball]\nmass = 1e-300\n", &["`ball.mass`", "1e-300"]);
}

#[test]
fn scenes_within_the_ranges_are_accepted() {
    // Edges of the physical bound: a thin shell (2/3) and a ring (1) of the paper's ball.
    for j in [3.15e-7, 5.25e-7, 7.875e-7, 0.0] {
        Scene::from_toml(&format!("[ball]\ninertia = {j:e}\n")).unwrap();
    }
    // A heavy end (tip 10⁴ × the beam) and a long offset (100 L) are odd but representable.
    Scene::from_toml("[tip]\nmass = 1160.0\noffset = 36.5\n[beam]\nmodulus = 2e15\n").unwrap();
    for spec in ["paper", "physics"] {
        Scene::load(spec).unwrap();
    }
    for f in [
        "locked",
        "tuned",
        "mast-arm",
        "mast-arm-second-mode",
        "mast-arm-von-karman",
    ] {
        let p = format!("{}/../scenes/{f}.toml", env!("CARGO_MANIFEST_DIR"));
        Scene::load(&p).unwrap_or_else(|e| panic!("{f}: {e:#}"));
    }
}

/// Before: `estimate --lab --load-step 1e12` iterated the Riccati equation for 43 s, then
/// "Riccati iteration did not converge", naming nothing. Now refused before the iteration,
/// naming the option, its value and the most it may be.
#[test]
fn a_load_step_the_filter_cannot_resolve_is_refused_by_name() {
    use absorber_sim::estimate::{lab, BaselineLoad};
    let huge = BaselineLoad {
        step: Some(1e12),
        time: 5.0,
    };
    let e = match lab(&Scene::paper(), 10.0, 0.05, huge) {
        Ok(_) => panic!("--load-step 1e12 accepted"),
        Err(e) => format!("{e:#}"),
    };
    for w in ["`--load-step`", "1e12", "allowed: at most"] {
        assert!(e.contains(w), "`{w}` not in: {e}");
    }
}
