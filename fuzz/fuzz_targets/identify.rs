//! Arbitrary bytes → `identify`'s record parser (CSV text: comments, header, rows) → the
//! identification with an arbitrary band and record kind. Never a panic; an error is one line;
//! a parsed record has a finite positive step and finite samples; a fit marked usable has a
//! finite f₁ inside the band asked for and a finite ζ ≥ 0.
#![no_main]
use absorber_sim::identify::{identify, parse_csv, RecordKind, Verdict};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let Some((&ctl, rest)) = bytes.split_first() else {
        return;
    };
    let text = String::from_utf8_lossy(rest);
    // Column names: the usual ones, or ones the text may lack.
    let (time, column) = match ctl % 4 {
        0 => ("t", "tip"),
        1 => ("t", "a"),
        2 => ("time", "x"),
        _ => ("t", "t"),
    };
    let rec = match parse_csv(&text, time, column) {
        Ok(r) => r,
        Err(e) => {
            assert!(!format!("{e:#}").contains('\n'), "{e:#}");
            return;
        }
    };
    assert!(rec.dt.is_finite() && rec.dt > 0.0 && rec.t0.is_finite());
    assert!(rec.x.iter().all(|x| x.is_finite()) && rec.x.len() >= 64);
    let kind = if ctl & 4 == 0 {
        RecordKind::Decay
    } else {
        RecordKind::Ambient
    };
    let nyquist = 0.5 / rec.dt;
    let band = match (ctl >> 3) % 4 {
        0 => None,
        1 => Some((0.1 * nyquist, 0.5 * nyquist)),
        2 => Some((0.0, 2.0 * nyquist)),
        _ => Some((nyquist, 0.1 * nyquist)),
    };
    match identify(&rec, kind, band, column) {
        Ok(id) if id.verdict == Verdict::Usable => {
            assert!(id.f1.is_finite() && id.f1 > 0.0, "{id:?}");
            assert!(id.zeta.is_finite() && id.zeta >= 0.0, "{id:?}");
            if let Some((lo, hi)) = band {
                assert!(id.f1 >= lo && id.f1 <= hi, "f1 {} outside {band:?}", id.f1);
            }
        }
        Ok(id) => assert!(!id.reasons.is_empty()),
        Err(e) => assert!(!format!("{e:#}").contains('\n'), "{e:#}"),
    }
});
