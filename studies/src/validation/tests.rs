//! The verdict rule of the chaotic claims.

use super::claims::{judge, Judged};
use absorber_sim::ensemble::Spread;

/// The verdict rule on bands placed by hand against the two criteria of the document.
#[test]
fn the_rule_judges_the_band_mean_plus_minus_sd() {
    let band = |mean: f64, sd: f64| Spread {
        mean,
        sd,
        min: mean - 2.0 * sd,
        max: mean + 2.0 * sd,
        k: 8,
    };
    let transfer = (f64::NEG_INFINITY, 0.2);
    assert_eq!(judge(&band(0.10, 0.05), transfer), Judged::Holds);
    assert_eq!(judge(&band(0.15, 0.08), transfer), Judged::Within);
    assert_eq!(judge(&band(0.25, 0.08), transfer), Judged::Within);
    assert_eq!(judge(&band(0.60, 0.30), transfer), Judged::Fails);
    let beat = (3.4, 4.4);
    assert_eq!(judge(&band(3.9, 0.4), beat), Judged::Holds);
    assert_eq!(judge(&band(3.3, 0.4), beat), Judged::Within);
    assert_eq!(judge(&band(2.9, 0.4), beat), Judged::Fails);
    // A band wider than the range straddles both bounds: not decided.
    assert_eq!(judge(&band(3.9, 1.0), beat), Judged::Within);
    // No member with a value: fails.
    assert_eq!(judge(&Spread::of(&[f64::NAN; 4]), beat), Judged::Fails);
}
