use super::Scene;

const ARM: &str = r#"
kind = "beam"
[beam]
length = 10.0
mass = 300.0
area = 5e-3
inertia = 1e-4
[arm]
root_diameter = 0.3
tip_diameter = 0.15
wall = 0.005
heads = [{ position = 9.0, mass = 20.0 }]
"#;

/// The new keys parse and bad values are rejected by key name.
#[test]
fn arm_loads_and_sensor_keys_are_validated_by_name() {
    let ok = format!(
        "{ARM}[[loads]]\ntype = \"truck-gust\"\npressure = 100.0\nfrom = 2.0\nto = 4.0\nduration = 0.5\ntimes = [1.0]\n"
    );
    assert!(Scene::from_toml(&ok).is_ok());
    let cases = [
        (ARM.replace("wall = 0.005", "wall = 0.2"), "arm.wall"),
        (ARM.replace("position = 9.0", "position = 11.0"), "`arm.heads[0].position`: 11"),
        (format!("{ARM}detail = \"F\"\n"), "arm.detail"),
        (
            format!("{ARM}[[loads]]\ntype = \"vortex-shedding\"\nspeed = -1.0\ndepth = 0.5\nstrouhal = 0.12\nlift_coefficient = 0.3\narea = 1.0\n"),
            "loads[0].speed",
        ),
        (
            format!("{ARM}[sensor]\nnoise_density_ug = 25.0\nbias_mg = 1.0\nrange_g = 2.0\nrate = 100.0\nbandwidth = 80.0\n"),
            "sensor.bandwidth",
        ),
        (
            "kind = \"beam\"\n[[loads]]\ntype = \"csv\"\nfile = \"x.csv\"\n".to_string(),
            "needs an `[arm]`",
        ),
    ];
    for (text, key) in cases {
        let e = Scene::from_toml(&text)
            .err()
            .map(|e| format!("{e:#}"))
            .unwrap_or_default();
        assert!(e.contains(key), "{key}: {e}");
    }
}
