use super::*;
use crate::scene::{Arm, BeamOnly, FreeBall, Loaded};
use crate::{Model, Params};

/// Paper beam without gravity: E I = 1.694 N·m², L = 0.365 m.
fn weightless() -> Params<f64> {
    Params {
        gravity: 0.0,
        ..Params::default()
    }
}

fn ei(p: &Params<f64>) -> f64 {
    p.beam.modulus * p.beam.inertia
}

/// Static tip deflection under a tip force P equals Euler–Bernoulli's `P L³ / 3EI` within
/// 1e-5 relative. Reference: closed form; cubic Hermite elements reproduce the cubic
/// deflection exactly, so the budget covers only the geometric nonlinearity, of order
/// (δ/L)² ≈ 7e-8 at δ = 0.1 mm, and the static Newton solve.
#[test]
fn static_tip_deflection_under_tip_force_matches_pl3_over_3ei_within_1e_5() {
    let p = weightless();
    let force = 0.01;
    let mut m = Model::<f64, Loaded<BeamOnly>, 8, 32>::new(p).expect("valid");
    m.set_loads(&Loads::uniform(force, 0.0)).expect("finite");
    m.solve_static().expect("static");
    let exact = force * p.beam.length.powi(3) / (3.0 * ei(&p));
    let got = m.tip_deflection();
    assert!((got / exact - 1.0).abs() < 1e-5, "{got} vs {exact}");
}

/// Static tip deflection under a uniform line load w equals `w L⁴ / 8EI` within 1e-5:
/// Hermite elements with the consistent load vector ([`Element::line_load_force`]) give
/// exact nodal displacements for a uniform load (the tip is a node), so again only the
/// geometric nonlinearity remains.
#[test]
fn static_tip_deflection_under_line_load_matches_wl4_over_8ei_within_1e_5() {
    let p = weightless();
    let w = -0.05;
    let mut m = Model::<f64, Loaded<BeamOnly>, 4, 16>::new(p).expect("valid");
    m.set_loads(&Loads::uniform(0.0, w)).expect("finite");
    m.solve_static().expect("static");
    let exact = w * p.beam.length.powi(4) / (8.0 * ei(&p));
    let got = m.tip_deflection();
    assert!((got / exact - 1.0).abs() < 1e-5, "{got} vs {exact}");
}

/// A loaded scene fed zero loads runs bit for bit like the paper's scene (1000 steps of
/// the free ball at 4.13 Hz, f32): the loads add exact zeros.
#[test]
fn loaded_scene_with_zero_loads_is_bit_identical_to_the_paper_scene() {
    let p = Params::<f32>::default();
    let mut a = Model::<f32, FreeBall, 3, 13>::at_rest(p, 0.0).expect("valid");
    let mut b = Model::<f32, Loaded<FreeBall>, 3, 13>::at_rest(p, 0.0).expect("valid");
    let zero = Loads::zero();
    let w = 2.0 * core::f32::consts::PI * 4.13;
    for k in 1..=1000 {
        let ydd = -0.5e-3 * w * w * (w * k as f32 * 0.003).sin();
        let ra = a.step(ydd);
        let rb = b.step_with_loads(ydd, &zero);
        assert_eq!(ra, rb);
        assert_eq!(a.state(), b.state(), "step {k}");
    }
}

/// Loads on a paper scene are an error naming `loads`; a NaN load is `NonFiniteInput`
/// and leaves the state and the held loads unchanged.
#[test]
fn load_errors_are_values_and_keep_the_state() {
    let p = Params::<f64>::default();
    let mut m = Model::<f64, FreeBall, 2, 9>::at_rest(p, 0.0).expect("valid");
    match m.step_with_loads(0.0, &Loads::zero()) {
        Err(Error::InvalidParameter { field, .. }) => assert_eq!(field, "loads"),
        other => panic!("{other:?}"),
    }
    let mut l = Model::<f64, Loaded<FreeBall>, 2, 9>::at_rest(p, 0.0).expect("valid");
    l.step_with_loads(0.0, &Loads::uniform(0.2, 0.0))
        .expect("step");
    let before = *l.state();
    let bad = Loads::uniform(f64::NAN, 0.0);
    assert_eq!(l.step_with_loads(0.0, &bad), Err(Error::NonFiniteInput));
    assert_eq!(*l.state(), before);
    assert_eq!(l.loads().map(|x| x.tip_force), Some(0.2));
    let huge = Loads::uniform(0.0, 2.0e6);
    assert_eq!(l.step_with_loads(0.0, &huge), Err(Error::InputOutOfRange));
}

fn tube(root: f64, tip: f64) -> ArmParams<f64> {
    ArmParams {
        root_diameter: root,
        tip_diameter: tip,
        wall: 0.004,
        density: 7850.0,
        point_masses: [PointMass {
            position: 0.0,
            mass: 0.0,
        }; MAX_POINT_MASSES],
    }
}

/// The calibration's bending gradient: a uniform tube's element `k` gets the harmonic
/// mean of `E·I · b (1 + g (2x/L − 1))` over it, against the closed form
/// `l / ∫ dx / (E·I b (1 + g (2x/L − 1))) = 2 g l E·I b / (L ln(φ₁/φ₀))` (φ at the element's
/// ends) within 1e-9 (5-point Gauss on `1/φ`, a smooth function varying by < 9 % over an
/// element); `g = 0` gives the plain section bit for bit; and a model without sections
/// refuses a gradient (naming the field) rather than ignore it.
#[test]
fn bending_gradient_scales_each_section_by_its_harmonic_mean() {
    let arm = tube(0.2, 0.2);
    let beam = BeamParams {
        length: 12.0,
        ..Params::<f64>::default().beam
    };
    let plain = Calibration::<f64>::default();
    let (b, g) = (1.17, 0.08);
    let graded = Calibration {
        bending_stiffness: b,
        bending_gradient: g,
        ..plain
    };
    let n = 3;
    for k in 0..n {
        let e0 = arm.element(&beam, &plain, k, n);
        let e1 = arm.element(&beam, &graded, k, n);
        let l = beam.length / n as f64;
        let phi = |x: f64| 1.0 + g * (2.0 * x / beam.length - 1.0);
        let (x0, x1) = (k as f64 * l, (k + 1) as f64 * l);
        let exact =
            2.0 * g * l * e0.bending_rigidity * b / (beam.length * (phi(x1) / phi(x0)).ln());
        assert!(
            (e1.bending_rigidity / exact - 1.0).abs() < 1e-9,
            "{k}: {} vs {exact}",
            e1.bending_rigidity
        );
        assert_eq!(e1.mass_per_length, e0.mass_per_length);
        let zero = Calibration {
            bending_gradient: 0.0,
            ..graded
        };
        let scaled = Calibration {
            bending_stiffness: b,
            ..plain
        };
        assert_eq!(
            arm.element(&beam, &zero, k, n),
            arm.element(&beam, &scaled, k, n)
        );
    }
    let p = Params {
        calibration: graded,
        ..Params::default()
    };
    match Model::<f64, Loaded<BeamOnly>, 3, 12>::new(p) {
        Err(Error::InvalidParameter { field, .. }) => {
            assert_eq!(field, "calibration.bending_gradient")
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
    let mut pa = p;
    pa.beam.length = beam.length;
    assert!(Model::<f64, Arm<BeamOnly>, 3, 12>::with_arm(pa, &arm).is_ok());
    for bad in [0.6, -0.6, f64::NAN] {
        let c = Calibration {
            bending_gradient: bad,
            ..plain
        };
        assert!(c.validate().is_err(), "{bad}");
    }
}

/// A uniform tube arm with a point mass at its end sags under gravity by
/// `ρA g L⁴/8EI + m g L³/3EI` within 1e-4 (closed form; nodal values of Hermite elements
/// are exact for both loads; (δ/L)² ≈ 2e-5 of geometric nonlinearity at δ/L = 0.4 %).
#[test]
fn uniform_arm_with_end_mass_sags_like_euler_bernoulli() {
    let mut p = Params::<f64>::default();
    p.beam.length = 6.0;
    let mut arm = tube(0.2, 0.2);
    arm.point_masses[0] = PointMass {
        position: 6.0,
        mass: 30.0,
    };
    let m = Model::<f64, Arm<BeamOnly>, 4, 16>::arm_at_rest(p, &arm, 0.0).expect("arm");
    let (a, i) = arm.section_at(0.0, 6.0);
    let e_i = p.beam.modulus * i;
    let g = p.gravity;
    let exact = -(7850.0 * a * g * 6f64.powi(4) / (8.0 * e_i) + 30.0 * g * 216.0 / (3.0 * e_i));
    let got = m.tip_deflection();
    assert!((got / exact - 1.0).abs() < 1e-4, "{got} vs {exact}");
    assert!((arm.total_mass(6.0) - (7850.0 * a * 6.0 + 30.0)).abs() < 1e-9);
}

/// Every point mass lands on exactly one element, whatever `x/l` rounds to: the vertical
/// weight over all elements (`Σ_k w₀ + w₂`, the Hermite position functions sum to 1) equals
/// the heads' mass for a head at the free end and at every interior node, for `N = 1..=16`,
/// in `f64` and `f32`. Before, the shipped mast arm (16.76 m, `N = 3`, `f64`) lost its 10 kg
/// end sign: `(L − 2l)/l = 1 + 2.2e-16`.
#[test]
fn every_head_lands_on_one_element() {
    fn total<T: Real>(arm: &ArmParams<T>, length: T, n: usize) -> f64 {
        (0..n)
            .map(|k| {
                let (_, w) = arm.point_mass_on(length, k, n);
                crate::scalar::to_f64(w[0] + w[2])
            })
            .sum()
    }
    let length = 16.76;
    for n in 1..=16 {
        for j in 0..=n {
            let mut arm = tube(0.33, 0.134);
            arm.point_masses[0] = PointMass {
                position: length * j as f64 / n as f64,
                mass: 10.0,
            };
            arm.point_masses[1] = PointMass {
                position: length,
                mass: 7.0,
            };
            let got = total(&arm, length, n);
            assert!((got - 17.0).abs() < 1e-12, "f64 N = {n}, node {j}: {got}");
            let arm32 = ArmParams::<f32> {
                root_diameter: 0.33,
                tip_diameter: 0.134,
                wall: 0.004,
                density: 7850.0,
                point_masses: arm.point_masses.map(|p| PointMass {
                    position: p.position as f32,
                    mass: p.mass as f32,
                }),
            };
            let got = total(&arm32, length as f32, n);
            assert!((got - 17.0).abs() < 1e-4, "f32 N = {n}, node {j}: {got}");
        }
    }
}

/// Invalid arm fields are rejected by name.
#[test]
fn arm_validation_names_the_field() {
    let p = Params::<f64>::default();
    let mut arm = tube(0.01, 0.006);
    let err = Model::<f64, Arm<BeamOnly>, 2, 8>::with_arm(p, &arm).err();
    assert!(matches!(
        err,
        Some(Error::InvalidParameter {
            field: "arm.wall",
            ..
        })
    ));
    arm.wall = 0.001;
    arm.point_masses[1] = PointMass {
        position: 1.0,
        mass: 1.0,
    };
    let err = Model::<f64, Arm<BeamOnly>, 2, 8>::with_arm(p, &arm).err();
    assert!(matches!(
        err,
        Some(Error::InvalidParameter {
            field: "arm.point_masses.position",
            ..
        })
    ));
}
