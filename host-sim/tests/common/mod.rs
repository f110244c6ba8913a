//! Helpers of the tests that run the `host-sim` binary and read what it wrote.
// Each test file uses the helpers it needs.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
}

pub fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-out-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn run(args: &[&str]) -> std::process::Output {
    bin().args(args).output().unwrap()
}

pub fn manifest(d: &Path, name: &str) -> serde_json::Value {
    let t = std::fs::read_to_string(d.join(format!("{name}.manifest.json"))).unwrap();
    serde_json::from_str(&t).unwrap()
}

pub fn names(v: &serde_json::Value) -> Vec<String> {
    v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap().to_string())
        .collect()
}

/// Visible (non-hidden) files of a directory, sorted.
pub fn visible(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| !n.starts_with('.'))
        .collect();
    v.sort();
    v
}
