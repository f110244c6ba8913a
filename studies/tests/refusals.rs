//! The studies' options are refused before any work, on one error line that names the option,
//! its value and what is allowed; a subset of the stability matrix never replaces the document.

use std::path::PathBuf;
use std::process::{Command, Output};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("absorber-studies-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_absorber-studies"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn options_are_refused_with_name_value_and_range() {
    let dir = tmp("matrix");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("s.md");
    let out = out.to_str().unwrap();
    let img = dir.to_str().unwrap();
    let cases: Vec<(Vec<&str>, i32, Vec<&str>)> = vec![
        (
            vec!["stability", "--only", "bogus", "--out", out],
            1,
            vec!["`--only`", "bogus", "groups: "],
        ),
        (
            vec!["stability", "--drift-duration", "-1", "--out", out],
            1,
            vec!["`--drift-duration`", "-1", "finite and positive"],
        ),
        (
            vec!["stability", "--jobs", "0", "--out", out],
            1,
            vec!["`--jobs`", "0", "at least 1"],
        ),
        (
            vec!["accuracy", "--repeats", "0", "--out", out],
            1,
            vec!["`--repeats`", "0", "at least 1"],
        ),
        (
            vec!["chaos", "--freqs", "-1", "--out", out],
            1,
            vec!["`--freqs`", "-1", "finite and positive"],
        ),
        (
            vec![
                "chaos",
                "--transient",
                "50",
                "--duration",
                "10",
                "--out",
                out,
            ],
            1,
            vec!["`--transient`", "50", "< `--duration` = 10"],
        ),
        (
            vec!["validation", "--converged", "0", "--out", out, "--img", img],
            1,
            vec!["`--converged`", "0", "4 ..= 256"],
        ),
        (
            vec!["run"],
            2,
            vec![
                "unknown command `run`",
                "allowed: stability, chaos, accuracy, validation",
            ],
        ),
    ];
    for (args, code, words) in cases {
        let o = Command::new(env!("CARGO_BIN_EXE_absorber-studies"))
            .args(&args)
            .current_dir(&dir)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
        let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
        assert_eq!(errors.len(), 1, "{args:?}: {err}");
        for w in words {
            assert!(
                errors[0].contains(w),
                "{args:?}: `{}` lacks `{w}`",
                errors[0]
            );
        }
    }
}

#[test]
fn stability_only_does_not_overwrite_the_document() {
    let doc = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/stability.md");
    let before = std::fs::read(doc).unwrap();
    for extra in [&[][..], &["--out", doc][..]] {
        let mut a = vec!["stability", "--only", "extreme", "--quick"];
        a.extend_from_slice(extra);
        let o = run(&a);
        assert_eq!(o.status.code(), Some(1), "{a:?}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("--only") && e.contains("--out"), "{e}");
    }
    assert_eq!(std::fs::read(doc).unwrap(), before);
}
