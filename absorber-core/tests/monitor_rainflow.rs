//! Streaming rainflow counting against ASTM E1049-85 and the Python `rainflow` package.

use absorber_core::monitor::{Cycle, DetailCategory, Miner, Rainflow, ThresholdRule};
use std::collections::BTreeMap;

/// Counts a whole history: closed cycles while streaming, then the residue as half cycles.
/// Returns distinct ranges (ascending) with their cycle counts, like `rainflow.count_cycles`.
fn count<const CAP: usize>(series: &[f64], gate: f64) -> (Vec<(f64, f64)>, Rainflow<f64, CAP>) {
    let mut rf = Rainflow::<f64, CAP>::new(gate).unwrap();
    let mut agg = BTreeMap::<u64, f64>::new();
    let mut add = |c: Cycle<f64>| *agg.entry(c.range.to_bits()).or_insert(0.0) += c.count();
    for &x in series {
        rf.push(x, &mut add).unwrap();
    }
    rf.residue(&mut add);
    let out = agg
        .into_iter()
        .map(|(b, n)| (f64::from_bits(b), n))
        .collect();
    (out, rf)
}

/// ASTM E1049-85 (2011) §5.4.4, Fig. 6: the history −2, 1, −3, 5, −1, 3, −4, 4, −2 gives
/// ranges 3 (½), 4 (1½), 6 (½), 8 (1), 9 (½) — exactly (Table 4 of the standard).
#[test]
fn astm_e1049_rainflow_example_is_reproduced_exactly() {
    let history = [-2.0, 1.0, -3.0, 5.0, -1.0, 3.0, -4.0, 4.0, -2.0];
    let expected = vec![(3.0, 0.5), (4.0, 1.5), (6.0, 0.5), (8.0, 1.0), (9.0, 0.5)];
    let (got, _) = count::<16>(&history, 0.0);
    assert_eq!(got, expected);
    // The same in f32, and with every point repeated and interpolated (not turning points).
    let mut rf = Rainflow::<f32, 16>::new(0.0).unwrap();
    let mut n = BTreeMap::<u32, f32>::new();
    let mut add = |c: Cycle<f32>| *n.entry(c.range.to_bits()).or_insert(0.0) += c.count();
    for w in history.windows(2) {
        for k in 0..4 {
            rf.push((w[0] + (w[1] - w[0]) * k as f64 / 4.0) as f32, &mut add)
                .unwrap();
        }
    }
    rf.push(-2.0, &mut add).unwrap();
    rf.residue(&mut add);
    let got32: Vec<(f64, f64)> = n
        .into_iter()
        .map(|(b, c)| (f32::from_bits(b) as f64, c as f64))
        .collect();
    assert_eq!(got32, expected);
}

struct Vectors {
    name: String,
    series: Vec<f64>,
    counts: Vec<(f64, f64)>,
}

fn load_vectors() -> Vec<Vectors> {
    let text = include_str!("data/rainflow_vectors.csv");
    let mut out: Vec<Vectors> = Vec::new();
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
    {
        let mut f = line.split(',');
        let kind = f.next().unwrap();
        let name = f.next().unwrap().to_string();
        let v: Vec<f64> = f.map(|x| x.parse().unwrap()).collect();
        match kind {
            "series" => out.push(Vectors {
                name,
                series: v,
                counts: Vec::new(),
            }),
            "counts" => {
                let s = out.last_mut().unwrap();
                assert_eq!(s.name, name);
                s.counts = v.chunks(2).map(|p| (p[0], p[1])).collect();
            }
            _ => panic!("unknown line kind {kind}"),
        }
    }
    out
}

/// Same ranges and counts, half cycles included, as `rainflow` 3.2.0 (`extract_cycles`, residue
/// counted as half cycles at the end) on three seeded 2000-point sequences: white noise, a
/// random walk, a beating sine with noise. Exact: every range is the same f64 difference.
#[test]
fn counts_equal_the_python_rainflow_package_exactly_on_random_sequences() {
    let vectors = load_vectors();
    assert_eq!(vectors.len(), 3);
    for v in &vectors {
        assert_eq!(v.series.len(), 2000);
        let (got, rf) = count::<512>(&v.series, 0.0);
        assert_eq!(rf.overflows(), 0, "{}", v.name);
        assert_eq!(
            got.len(),
            v.counts.len(),
            "{}: number of distinct ranges",
            v.name
        );
        for (g, e) in got.iter().zip(&v.counts) {
            assert_eq!(g, e, "{}", v.name);
        }
        let total: f64 = got.iter().map(|c| c.1).sum();
        println!(
            "{}: {} distinct ranges, {total} cycles, residue {} points: identical",
            v.name,
            got.len(),
            rf.residue_len()
        );
    }
}

/// Batch E1049 counting of a whole history (reference for the streaming state).
fn batch(series: &[f64]) -> Vec<(f64, f64)> {
    count::<4096>(series, 0.0).0
}

/// The residue can be read at any time without disturbing the stream: after every prefix,
/// streaming closed cycles + residue equal the batch count of that prefix.
#[test]
fn residue_on_demand_equals_the_count_of_the_history_so_far() {
    let v = &load_vectors()[2];
    let mut rf = Rainflow::<f64, 512>::new(0.0).unwrap();
    let mut closed = BTreeMap::<u64, f64>::new();
    for (k, &x) in v.series.iter().enumerate() {
        rf.push(x, &mut |c: Cycle<f64>| {
            *closed.entry(c.range.to_bits()).or_insert(0.0) += c.count()
        })
        .unwrap();
        if k % 97 == 0 || k == v.series.len() - 1 {
            let mut all = closed.clone();
            rf.residue(&mut |c: Cycle<f64>| {
                *all.entry(c.range.to_bits()).or_insert(0.0) += c.count()
            });
            let got: Vec<(f64, f64)> = all
                .into_iter()
                .map(|(b, n)| (f64::from_bits(b), n))
                .collect();
            assert_eq!(got, batch(&v.series[..=k]), "prefix of {} points", k + 1);
        }
    }
}

/// A full residue drops the pair (p₂, p₃) as one cycle of range |p₁ − p₂|: never less damage
/// than the unbounded counter (m = 3 and m = 5, 300 random ring-down + burst histories), and
/// identical when it does not overflow.
#[test]
fn residue_overflow_is_counted_conservatively() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut overflowed = 0;
    for trial in 0..300 {
        let mut series = Vec::new();
        for _burst in 0..4 {
            // Ring-down (a long converging residue), then a random burst.
            let (mut a, r, c) = (
                1.0 + 9.0 * uniform(),
                0.80 + 0.19 * uniform(),
                uniform() - 0.5,
            );
            for k in 0..40 {
                series.push(c + if k % 2 == 0 { a } else { -a });
                a *= r;
            }
            for _ in 0..(uniform() * 10.0) as usize {
                series.push(30.0 * (uniform() - 0.5));
            }
        }
        for m in [3.0, 5.0] {
            let curve = absorber_core::monitor::SnCurve {
                slope: m,
                reference_range: 1.0,
                threshold: 0.0,
                rule: ThresholdRule::Extended,
            };
            let damage = |pairs: &[(f64, f64)]| -> f64 {
                pairs
                    .iter()
                    .map(|(r, n)| n * curve.damage_per_cycle(*r))
                    .sum()
            };
            let (small, rf) = count::<6>(&series, 0.0);
            let (big, rf_big) = count::<4096>(&series, 0.0);
            assert_eq!(rf_big.overflows(), 0);
            let (ds, db) = (damage(&small), damage(&big));
            if rf.overflows() == 0 {
                assert_eq!(small, big);
            } else {
                overflowed += 1;
                assert!(
                    ds >= db * (1.0 - 1e-12),
                    "trial {trial}, m = {m}: {ds} < {db}"
                );
            }
        }
    }
    assert!(
        overflowed > 100,
        "the test must exercise the overflow ({overflowed})"
    );
}

/// The hysteresis gate ignores reversals of at most `gate`: 0, 10, 9.5, 10.2, 0 with a gate of 1
/// counts as 0, 10.2, 0 (two half cycles of 10.2); without it the 0.5 dip is a reversal.
#[test]
fn hysteresis_gate_ignores_small_reversals() {
    let h = [0.0, 10.0, 9.5, 10.2, 0.0];
    assert_eq!(count::<8>(&h, 1.0).0, vec![(10.2, 1.0)]);
    let (no_gate, _) = count::<8>(&h, 0.0);
    assert!(no_gate.iter().any(|&(r, _)| (r - 0.5).abs() < 1e-12));
    assert!(Rainflow::<f64, 8>::new(-1.0).is_err());
    assert!(Rainflow::<f64, 8>::new(f64::NAN).is_err());
    let mut rf = Rainflow::<f64, 8>::new(0.0).unwrap();
    assert!(rf.push(f64::NAN, &mut |_| {}).is_err());
    assert_eq!(rf.reversals(), 0);
}

/// The monitor's Miner accumulator takes the residue without changing the running state.
#[test]
fn damage_with_residue_leaves_the_stream_untouched() {
    let mut rf = Rainflow::<f64, 16>::new(0.0).unwrap();
    let mut miner = Miner::new(DetailCategory::E.curve(ThresholdRule::Extended)).unwrap();
    for &x in &[-2.0e7, 1.0e7, -3.0e7, 5.0e7, -1.0e7, 3.0e7, -4.0e7, 4.0e7] {
        rf.push(x, &mut |c| miner.add(&c)).unwrap();
    }
    let before = (miner, rf.residue_points().to_vec());
    let with = miner.with_residue(&rf);
    let again = miner.with_residue(&rf);
    assert_eq!(with, again);
    assert!(with.damage() > miner.damage());
    assert_eq!((miner, rf.residue_points().to_vec()), before);
}
