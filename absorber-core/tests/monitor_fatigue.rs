//! Miner damage against closed forms; AASHTO presets against the specification's SI table.

use absorber_core::monitor::fatigue::{KSI, REFERENCE_CYCLES};
use absorber_core::monitor::{DetailCategory, Miner, Rainflow, ThresholdRule};

/// Runs `periods` periods of `mean − (S/2) cos(2π t)` (starting and ending in a valley),
/// 40 samples per period, through rainflow + Miner (residue included).
fn sine<T: absorber_core::Real>(
    range: f64,
    periods: usize,
    rule: ThresholdRule,
    cat: DetailCategory,
) -> (Miner<T>, u64) {
    let mut rf = Rainflow::<T, 16>::new(T::zero()).unwrap();
    let mut miner = Miner::<T>::new(cat.curve(rule)).unwrap();
    for k in 0..=periods * 40 {
        let x = 60e6 - 0.5 * range * (2.0 * std::f64::consts::PI * k as f64 / 40.0).cos();
        rf.push(nalgebra::convert(x), &mut |c| miner.add(&c))
            .unwrap();
    }
    (miner.with_residue(&rf), rf.overflows())
}

/// Constant-amplitude sine of range S, n periods: D = n S^m / A exactly (A = the category
/// constant, m = 3), S_eq = S; zero below the CAFT with the cutoff rule, n S^m / A with the
/// extended line. Budget 1e-12 (f64 rounding of a sum of 2n equal terms).
#[test]
fn miner_damage_of_a_constant_amplitude_sine_is_the_closed_form() {
    let cat = DetailCategory::EPrime;
    let a_pa3 = cat.constant_ksi3() * KSI.powi(3);
    let caft = cat.threshold_ksi() * KSI;
    let n = 1000;
    for range in [25e6, 40e6, 120e6] {
        let (m, overflows) = sine::<f64>(range, n, ThresholdRule::Cutoff, cat);
        assert_eq!(overflows, 0);
        let closed = n as f64 * range.powi(3) / a_pa3;
        assert!((m.cycles() - n as f64).abs() < 1e-12);
        assert!(
            (m.damage() - closed).abs() <= 1e-12 * closed,
            "S = {range}: D = {} vs n S³/A = {closed}",
            m.damage()
        );
        assert!((m.equivalent_range() - range).abs() <= 1e-9 * range);
        println!(
            "S = {:.0} MPa, n = {n}: D = {:.9e}, n S^3/A = {closed:.9e}",
            range / 1e6,
            m.damage()
        );
    }
    // Below the threshold (17.9 MPa for E′).
    let below = 0.9 * caft;
    let (m, _) = sine::<f64>(below, n, ThresholdRule::Cutoff, cat);
    assert_eq!(m.damage(), 0.0);
    assert_eq!(m.damage_with(ThresholdRule::AllOnceExceeded), 0.0);
    let closed = n as f64 * below.powi(3) / a_pa3;
    assert!((m.damage_with(ThresholdRule::Extended) - closed).abs() <= 1e-12 * closed);
    // Cycles to failure: N(S₂) = 2e6, N(CAFT) = ∞ with the cutoff.
    let curve = cat.curve::<f64>(ThresholdRule::Cutoff);
    assert!((curve.cycles_to_failure(curve.reference_range) - REFERENCE_CYCLES).abs() < 1e-3);
    assert!(curve.cycles_to_failure(caft) > 1e300);
}

/// In f32 the compensated sums keep 10⁶ cycles of 10⁻⁹ damage each: same D as f64 within
/// 1e-5 relative (plain f32 summation would stall near 2⁻²⁴ of the total).
#[test]
fn f32_damage_accumulates_a_million_small_cycles() {
    let cat = DetailCategory::EPrime;
    let (m32, _) = sine::<f32>(30e6, 20_000, ThresholdRule::Cutoff, cat);
    let (m64, _) = sine::<f64>(30e6, 20_000, ThresholdRule::Cutoff, cat);
    let rel = (m32.damage() as f64 - m64.damage()).abs() / m64.damage();
    assert!(
        rel < 1e-5,
        "f32 {} vs f64 {} ({rel:e})",
        m32.damage(),
        m64.damage()
    );
    let mut m = Miner::<f32>::new(cat.curve(ThresholdRule::Extended)).unwrap();
    let c = absorber_core::monitor::Cycle {
        range: 1.0e6f32,
        mean: 0.0,
        full: true,
    };
    for _ in 0..1_000_000 {
        m.add(&c);
    }
    let expected = 1e6
        * cat
            .curve::<f64>(ThresholdRule::Extended)
            .damage_per_cycle(1.0e6);
    let rel = (m.damage() as f64 - expected).abs() / expected;
    assert!(rel < 1e-5, "{} vs {expected} ({rel:e})", m.damage());
}

/// The presets equal AASHTO LRFD Table 6.6.1.2.5-1 / -3 in SI units (A in 10¹¹ MPa³ and
/// (ΔF)_TH in MPa as printed in the SI edition, which rounds to 3 digits): within 0.5 %.
#[test]
fn aashto_presets_match_the_si_table() {
    let si = [
        (DetailCategory::A, 82.0, 165.0),
        (DetailCategory::B, 39.3, 110.0),
        (DetailCategory::BPrime, 20.0, 82.7),
        (DetailCategory::C, 14.4, 69.0),
        (DetailCategory::CPrime, 14.4, 82.7),
        (DetailCategory::D, 7.21, 48.3),
        (DetailCategory::E, 3.61, 31.0),
        (DetailCategory::EPrime, 1.28, 17.9),
    ];
    for (cat, a_si, th_si) in si {
        let c = cat.curve::<f64>(ThresholdRule::Cutoff);
        let a_mpa3 = REFERENCE_CYCLES * (c.reference_range / 1e6).powi(3);
        assert!(
            (a_mpa3 / 1e11 / a_si - 1.0).abs() < 5e-3,
            "{}: A",
            cat.name()
        );
        assert!(
            (c.threshold / 1e6 / th_si - 1.0).abs() < 5e-3,
            "{}: CAFT",
            cat.name()
        );
        assert_eq!(c.slope, 3.0);
    }
    assert!(Miner::<f64>::new(absorber_core::monitor::SnCurve {
        slope: -3.0,
        reference_range: 1.0,
        threshold: 0.0,
        rule: ThresholdRule::Cutoff
    })
    .is_err());
}

/// `StressDamage` (the estimator's fatigue counter) on a constant-amplitude sine of range S,
/// n periods, the residue included: the extended damage is n (S/S₂)^m / 2·10⁶ exactly as
/// Miner's closed form, the cutoff damage the same above the CAFT and zero below it; every
/// closed cycle reaches the callback with range S.
#[test]
fn stress_damage_counts_a_sine_as_the_closed_form() {
    use absorber_core::monitor::StressDamage;
    let cat = DetailCategory::EPrime;
    let curve = cat.curve::<f64>(ThresholdRule::Extended);
    let caft = cat.threshold_ksi() * KSI;
    for range in [0.5 * caft, 3.0 * caft] {
        let mut d = StressDamage::<f64, 16>::new(cat).unwrap();
        let mut closed = Vec::new();
        let periods = 25;
        for k in 0..=periods * 40 {
            let x = 60e6 - 0.5 * range * (2.0 * std::f64::consts::PI * k as f64 / 40.0).cos();
            d.push(x, &mut |c| closed.push(c.range)).unwrap();
        }
        let (extended, cutoff) = d.damage();
        let want = periods as f64 * curve.damage_per_cycle(range);
        assert!(
            (extended / want - 1.0).abs() < 1e-12,
            "{extended} vs {want}"
        );
        if range > caft {
            assert!((cutoff / want - 1.0).abs() < 1e-12);
        } else {
            assert_eq!(cutoff, 0.0);
        }
        assert!(!closed.is_empty());
        assert!(closed.iter().all(|r| (r / range - 1.0).abs() < 1e-12));
        assert!(
            d.push(f64::NAN, &mut |_| {}).is_err(),
            "a non-finite stress is an error"
        );
    }
}
