//! The committed header `include/absorber.h` is what cbindgen makes of `src/lib.rs` today.
//! A change to the API without regenerating the header fails here (`cargo test`, so CI).
//! Regenerate: `ABSORBER_BLESS=1 cargo test -p absorber-ffi --test header`.

use std::path::Path;

fn generate() -> String {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen parses src/lib.rs");
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).expect("UTF-8 header")
}

#[test]
fn committed_header_matches_the_code() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("include/absorber.h");
    let fresh = generate();
    if std::env::var_os("ABSORBER_BLESS").is_some() {
        std::fs::write(&path, &fresh).expect("write include/absorber.h");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != fresh {
        let line = committed
            .lines()
            .zip(fresh.lines())
            .position(|(a, b)| a != b)
            .map_or(committed.lines().count().min(fresh.lines().count()), |i| i)
            + 1;
        panic!(
            "absorber-ffi/include/absorber.h is out of date with src/lib.rs (first difference at line \
             {line}); regenerate it with `ABSORBER_BLESS=1 cargo test -p absorber-ffi --test header` \
             and commit it"
        );
    }
}

#[test]
fn header_declares_every_exported_function() {
    let header = generate();
    let src = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs"))
        .expect("src/lib.rs");
    let mut n = 0;
    for line in src.lines() {
        let Some(rest) = line.split("extern \"C\" fn ").nth(1) else {
            continue;
        };
        let name = rest.split('(').next().unwrap_or_default();
        assert!(
            header.contains(&format!("{name}(")),
            "{name} missing from the header"
        );
        n += 1;
    }
    assert!(n >= 20, "only {n} exported functions found");
}
