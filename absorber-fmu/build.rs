//! `BUILD_ID`: a hash of this crate's and the core's sources, compiled into the shared library
//! and into host-sim, so that `host-sim fmu` never packages a library of other sources.

use std::hash::Hasher;
use std::path::Path;

/// FNV-1a, 64 bit.
struct Fnv(u64);
impl Hasher for Fnv {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 = (self.0 ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

fn files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut paths = Vec::new();
    for dir in [root.join("src"), root.join("../absorber-core/src")] {
        println!("cargo:rerun-if-changed={}", dir.display());
        files(&dir, &mut paths);
    }
    paths.sort();
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    for p in &paths {
        if let (Some(name), Ok(text)) = (p.file_name(), std::fs::read(p)) {
            h.write(name.to_string_lossy().as_bytes());
            h.write(&text);
        }
    }
    println!("cargo:rustc-env=ABSORBER_FMU_BUILD_ID={:016x}", h.finish());
}
