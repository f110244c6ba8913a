//! The committed docs/stability.md says what `absorber-studies stability` says today: the hardest
//! extreme cases (50 mm at 4.13 Hz, 3.4 g, on the core in f32 and f64) run again through the
//! binary under test and their outcome and simulated time must equal the committed rows. (The
//! document once showed "✅ 20 s bounded" for f32 at 50 mm while the command failed at 6.04 s.)

use std::process::Command;

/// `(case, solver) → (simulated time, outcome up to its first parenthesis)` of a stability table.
fn rows(text: &str, case: &str) -> Vec<(String, String, String)> {
    text.lines()
        .filter(|l| l.starts_with("| extreme |"))
        .map(|l| l.split('|').map(str::trim).collect::<Vec<_>>())
        .filter(|c| c.len() > 8 && c[2] == case && c[3].starts_with("core"))
        .map(|c| {
            let outcome = c[8].split(" (").next().unwrap_or("").to_string();
            (c[3].to_string(), c[7].to_string(), outcome)
        })
        .collect()
}

#[test]
fn committed_stability_rows_are_what_the_command_prints() {
    let case = "amplitude 50 mm at 4.13 Hz";
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/stability.md"))
        .unwrap();
    let committed = rows(&doc, case);
    assert_eq!(committed.len(), 2, "{committed:?}");
    let out = std::env::temp_dir().join(format!("stability-{}.md", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_absorber-studies"))
        .args(["stability", "--only", case, "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let fresh = std::fs::read_to_string(&out).unwrap_or_default();
    let now = rows(&fresh, case);
    assert_eq!(
        now,
        committed,
        "docs/stability.md is out of date with `absorber-studies stability` (regenerate it: cargo run --release -p absorber-studies -- stability); stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}
