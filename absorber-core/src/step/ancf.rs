//! Planar ANCF cable element (gradient deficient), paper eqs. 1–17.
//!
//! Nodal coordinates per node: `[r₁, r₂, ∂r₁/∂x, ∂r₂/∂x]`; element vector `e = [node i; node j]`.
//! Position `r(x) = S(ξ) e` with the Hermite cubics of eq. 5, `ξ = x / l`.
//!
//! **Displacement form.** Every function here takes the element's *displacement* from the
//! straight reference configuration, `u = e − e_ref` with `e_ref = [x_i, 0, 1, 0, x_j, 0, 1, 0]`.
//! Mass, bending and gravity terms are linear, and `K_b e_ref = 0` (the reference is straight),
//! so they read the same in `u`. The axial Green strain `ε = ½(r′ᵀr′ − 1)` (eq. 11) is evaluated
//! as `ε = d₁ + ½(d₁² + d₂²)` with `d = S_x u = r′ − (1, 0)`, which is exact and never
//! subtracts 1 from a number close to 1 (in `f32` that subtraction alone would lose the strain).
//!
//! This module is the single source of truth for the element integrals: the embedded model
//! (`absorber-core`) and the full solver (`host-sim`) both call it.

use crate::params::{BeamParams, Calibration};
use crate::scalar::{lit, Real};
use nalgebra::{SMatrix, SVector, Vector2};

/// 8×8 element matrix.
pub type ElementMatrix<T> = SMatrix<T, 8, 8>;
/// 8-vector of element coordinates or forces.
pub type ElementVector<T> = SVector<T, 8>;

/// 5-point Gauss–Legendre rule on `[0, 1]`: exact to degree 9. The axial force and tangent
/// integrands are of degree 8 in ξ (ε is of degree 4, `S_xᵀ r′` of degree 4), so the rule
/// integrates them exactly.
pub(crate) const GAUSS5: [(f64, f64); 5] = [
    (0.046_910_077_030_668_004, 0.118_463_442_528_094_54),
    (0.230_765_344_947_158_45, 0.239_314_335_249_683_23),
    (0.5, 0.284_444_444_444_444_45),
    (0.769_234_655_052_841_5, 0.239_314_335_249_683_23),
    (0.953_089_922_969_332, 0.118_463_442_528_094_54),
];

/// One uniform ANCF cable element: length and section properties, SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element<T> {
    /// Element length l \[m\].
    pub length: T,
    /// Axial rigidity E·a \[N\].
    pub axial_rigidity: T,
    /// Bending rigidity E·I \[N·m²\].
    pub bending_rigidity: T,
    /// Mass per unit length ρ·a \[kg/m\].
    pub mass_per_length: T,
}

/// Hermite shape functions `[s1, s2, s3, s4]` at ξ (eq. 5).
#[inline]
pub fn shape<T: Real>(l: T, xi: T) -> [T; 4] {
    let (one, two, three) = (T::one(), lit::<T>(2.0), lit::<T>(3.0));
    let xi2 = xi * xi;
    let xi3 = xi2 * xi;
    [
        one - three * xi2 + two * xi3,
        l * (xi - two * xi2 + xi3),
        three * xi2 - two * xi3,
        l * (xi3 - xi2),
    ]
}

/// First x-derivatives `∂s_k/∂x` at ξ \[1/m for s1, s3; 1 for s2, s4\].
#[inline]
pub fn shape_x<T: Real>(l: T, xi: T) -> [T; 4] {
    let six = lit::<T>(6.0);
    let xi2 = xi * xi;
    [
        (six * xi2 - six * xi) / l,
        T::one() - lit::<T>(4.0) * xi + lit::<T>(3.0) * xi2,
        (six * xi - six * xi2) / l,
        lit::<T>(3.0) * xi2 - lit::<T>(2.0) * xi,
    ]
}

/// Second x-derivatives `∂²s_k/∂x²` at ξ.
#[inline]
pub fn shape_xx<T: Real>(l: T, xi: T) -> [T; 4] {
    let (six, twelve) = (lit::<T>(6.0), lit::<T>(12.0));
    [
        (twelve * xi - six) / (l * l),
        (six * xi - lit::<T>(4.0)) / l,
        (six - twelve * xi) / (l * l),
        (six * xi - lit::<T>(2.0)) / l,
    ]
}

/// `Σ_k w_k · (u_{2k}, u_{2k+1})`: applies a scalar shape row to the element vector.
/// (Exact-size chunks and slice patterns: no index assertion survives into firmware at any
/// optimization level.)
#[inline]
fn apply<T: Real>(w: &[T; 4], u: &ElementVector<T>) -> Vector2<T> {
    let mut r = Vector2::zeros();
    for (pair, wk) in u.as_slice().chunks_exact(2).zip(w.iter()) {
        if let [x, y] = pair {
            r.x += *x * *wk;
            r.y += *y * *wk;
        }
    }
    r
}

/// Expands a 4×4 scalar matrix `a` into the 8×8 `a ⊗ I₂` (both directions share the shape).
fn kron_i2<T: Real>(a: &SMatrix<T, 4, 4>) -> ElementMatrix<T> {
    let mut m = ElementMatrix::zeros();
    for i in 0..4 {
        for j in 0..4 {
            m[(2 * i, 2 * j)] = a[(i, j)];
            m[(2 * i + 1, 2 * j + 1)] = a[(i, j)];
        }
    }
    m
}

impl<T: Real> Element<T> {
    /// One of `n` equal elements of the beam `b`: length L/n, E·a and E·I times the calibration's
    /// factors ([`Calibration`]; 1 = the paper's element, bit for bit), ρa = m/L. The core and
    /// the full solver both build their element here.
    pub fn of_beam(b: &BeamParams<T>, calibration: &Calibration<T>, n: usize) -> Self {
        Self {
            length: b.length / lit::<T>(n as f64),
            axial_rigidity: b.modulus * b.area * calibration.axial_stiffness,
            bending_rigidity: b.modulus * b.inertia * calibration.bending_stiffness,
            mass_per_length: b.mass / b.length,
        }
    }

    /// Element mass `ρ a l` \[kg\].
    pub fn mass(&self) -> T {
        self.mass_per_length * self.length
    }

    /// Consistent mass matrix `M = ∫ ρ Sᵀ S dV` (eq. 8), closed form `ρ a l / 420 · [...] ⊗ I₂`.
    pub fn mass_matrix(&self) -> ElementMatrix<T> {
        let l = self.length;
        let c = self.mass_per_length * l / lit::<T>(420.0);
        let f = |x: f64| lit::<T>(x);
        let a = SMatrix::<T, 4, 4>::new(
            f(156.0),
            f(22.0) * l,
            f(54.0),
            f(-13.0) * l,
            f(22.0) * l,
            f(4.0) * l * l,
            f(13.0) * l,
            f(-3.0) * l * l,
            f(54.0),
            f(13.0) * l,
            f(156.0),
            f(-22.0) * l,
            f(-13.0) * l,
            f(-3.0) * l * l,
            f(-22.0) * l,
            f(4.0) * l * l,
        ) * c;
        kron_i2(&a)
    }

    /// HRZ-lumped mass matrix (Hinton, Rock & Zienkiewicz 1976): the diagonal of the
    /// consistent one scaled so that the translations carry the element mass,
    /// `ρ a l · diag(½, l²/78, ½, l²/78) ⊗ I₂` (positive definite: the slopes keep a rotary
    /// mass, unlike a plain row-sum lumping, which leaves them massless).
    pub fn lumped_mass_matrix(&self) -> ElementMatrix<T> {
        let l = self.length;
        let m = self.mass_per_length * l;
        let (half, rot) = (m * lit::<T>(0.5), m * l * l / lit::<T>(78.0));
        kron_i2(&SMatrix::<T, 4, 4>::from_diagonal(&nalgebra::Vector4::new(
            half, rot, half, rot,
        )))
    }

    /// Blend of the consistent and the HRZ-lumped mass, `(1 − μ) M_c + μ M_l` (μ =
    /// `lumping` ∈ \[0, 1\]; μ = 0 returns [`Element::mass_matrix`] bit for bit). Both have the
    /// element's mass in translation, so the blend keeps it.
    pub fn blended_mass_matrix(&self, lumping: T) -> ElementMatrix<T> {
        let consistent = self.mass_matrix();
        if lumping == T::zero() {
            return consistent;
        }
        consistent * (T::one() - lumping) + self.lumped_mass_matrix() * lumping
    }

    /// Constant bending stiffness `K_t = ∫ EI S″ᵀ S″ dx` (eq. 13 with κ = |r″|, eq. 11),
    /// closed form `EI / l³ · [...] ⊗ I₂`.
    pub fn bending_stiffness(&self) -> ElementMatrix<T> {
        let l = self.length;
        let c = self.bending_rigidity / (l * l * l);
        let f = |x: f64| lit::<T>(x);
        let a = SMatrix::<T, 4, 4>::new(
            f(12.0),
            f(6.0) * l,
            f(-12.0),
            f(6.0) * l,
            f(6.0) * l,
            f(4.0) * l * l,
            f(-6.0) * l,
            f(2.0) * l * l,
            f(-12.0),
            f(-6.0) * l,
            f(12.0),
            f(-6.0) * l,
            f(6.0) * l,
            f(2.0) * l * l,
            f(-6.0) * l,
            f(4.0) * l * l,
        ) * c;
        kron_i2(&a)
    }

    /// Generalized weight of the element for a downward field `g_eff` \[m/s²\] (eqs. 16–17):
    /// `Q_f = −g_eff ρ a l [0, ½, 0, l/12, 0, ½, 0, −l/12]ᵀ`.
    pub fn gravity_force(&self, g_eff: T) -> ElementVector<T> {
        let l = self.length;
        let w = self.mass() * g_eff;
        let half = lit::<T>(0.5);
        let twelfth = l / lit::<T>(12.0);
        let mut q = ElementVector::zeros();
        q[1] = -w * half;
        q[3] = -w * twelfth;
        q[5] = -w * half;
        q[7] = w * twelfth;
        q
    }

    /// Generalized force of a uniform vertical line load `w` \[N/m, positive up\] on the
    /// element, `Q_w = ∫ S₂ᵀ w dx = w l [0, ½, 0, l/12, 0, ½, 0, −l/12]ᵀ` (the integral of the
    /// Hermite cubics of eq. 5; the same vector as [`Element::gravity_force`] with `−ρ a g_eff`
    /// replaced by `w`). The one source of the load integral for the core and the full solver.
    pub fn line_load_force(&self, w: T) -> ElementVector<T> {
        let l = self.length;
        let total = w * l;
        let half = lit::<T>(0.5);
        let twelfth = l / lit::<T>(12.0);
        let mut q = ElementVector::zeros();
        q[1] = total * half;
        q[3] = total * twelfth;
        q[5] = total * half;
        q[7] = -total * twelfth;
        q
    }

    /// Axial Green strain at ξ from the displacement `u` (eq. 11, cancellation free).
    pub fn axial_strain(&self, u: &ElementVector<T>, xi: T) -> T {
        self.axial_point(u, xi).1
    }

    /// Curvature vector `r″ = S_xx u` at ξ \[1/m\] (the paper's κ = |r″|).
    pub fn curvature_vector(&self, u: &ElementVector<T>, xi: T) -> Vector2<T> {
        apply(&shape_xx(self.length, xi), u)
    }

    /// At Gauss point ξ: the shape derivatives, the strain ε and `g = S_xᵀ r′` (8-vector).
    #[inline]
    fn axial_point(&self, u: &ElementVector<T>, xi: T) -> ([T; 4], T, ElementVector<T>) {
        let sx = shape_x(self.length, xi);
        let d = apply(&sx, u);
        let eps = d.x + lit::<T>(0.5) * d.norm_squared();
        let (r1, r2) = (T::one() + d.x, d.y); // r′ = (1 + d₁, d₂)
        let mut g = ElementVector::zeros();
        for (pair, s) in g.as_mut_slice().chunks_exact_mut(2).zip(sx.iter()) {
            if let [gx, gy] = pair {
                *gx = *s * r1;
                *gy = *s * r2;
            }
        }
        (sx, eps, g)
    }

    /// The axial terms' data at the Gauss points, computed once (see [`AxialQuadrature`]).
    pub fn axial_quadrature(&self) -> AxialQuadrature<T> {
        let mut q = AxialQuadrature {
            sx: [[T::zero(); 4]; 5],
            weight: [T::zero(); 5],
        };
        for ((sx, w), (xi, wg)) in q.sx.iter_mut().zip(q.weight.iter_mut()).zip(GAUSS5) {
            *sx = shape_x(self.length, lit::<T>(xi));
            *w = self.axial_rigidity * self.length * lit::<T>(wg);
        }
        q
    }

    /// Axial elastic force `Q_l = ∫ EA ε S_xᵀ r′ dx` (eqs. 12–13), by 5-point Gauss (exact).
    pub fn axial_force(&self, u: &ElementVector<T>) -> ElementVector<T> {
        self.axial_quadrature().force(u)
    }

    /// Axial elastic force (as [`Element::axial_force`]) and its exact tangent
    /// `K_l = ∫ EA [(S_xᵀ r′)(S_xᵀ r′)ᵀ + ε S_xᵀ S_x] dx`, by 5-point Gauss (exact), as a full
    /// 8×8 matrix (the full solver's form; the core adds [`AxialQuadrature::tangent`]'s blocks
    /// straight into its band).
    pub fn axial_force_and_tangent(
        &self,
        u: &ElementVector<T>,
    ) -> (ElementVector<T>, ElementMatrix<T>) {
        let quad = self.axial_quadrature();
        let mut tangent = ElementMatrix::zeros();
        let force = quad.tangent(u, |row, col, value| {
            if let Some(t) = tangent.get_mut((row, col)) {
                *t = value;
            }
        });
        (force, tangent)
    }

    /// Axial strain energy `½ ∫ EA ε² dx` \[J\] (5-point Gauss: exact for the degree-8 integrand).
    pub fn axial_energy(&self, u: &ElementVector<T>) -> T {
        let mut e = T::zero();
        // The points and half weights converted before the loop (folded to constants: the
        // loop is not unrolled, and `f64` arithmetic in it is software on an FPv4-SP core).
        let points = GAUSS5.map(|(xi, w)| (lit::<T>(xi), lit::<T>(0.5 * w)));
        for (xi, half_w) in points {
            let (_, eps, _) = self.axial_point(u, xi);
            e += half_w * self.axial_rigidity * self.length * eps * eps;
        }
        e
    }

    /// Bending strain energy `½ uᵀ K_t u` \[J\].
    pub fn bending_energy(&self, u: &ElementVector<T>) -> T {
        Self::bending_energy_with(&self.bending_stiffness(), u)
    }

    /// [`Element::bending_energy`] with `K_t` given: `stiffness` must be this element's
    /// [`Element::bending_stiffness`], computed once (as [`crate::step::beam::Beam`] keeps it) instead
    /// of at every call. Same result bit for bit.
    pub fn bending_energy_with(stiffness: &ElementMatrix<T>, u: &ElementVector<T>) -> T {
        lit::<T>(0.5) * u.dot(&(stiffness * u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn el() -> Element<f64> {
        Element {
            length: 0.2,
            axial_rigidity: 8.12e6,
            bending_rigidity: 1.694,
            mass_per_length: 0.3178,
        }
    }

    /// The closed-form matrices equal their defining integrals (Gauss, exact for these degrees).
    #[test]
    fn closed_form_mass_and_bending_equal_quadrature() {
        let e = el();
        let (l, mut m, mut k) = (
            e.length,
            ElementMatrix::<f64>::zeros(),
            ElementMatrix::<f64>::zeros(),
        );
        for (xi, w) in GAUSS5 {
            let s = shape(l, xi);
            let sxx = shape_xx(l, xi);
            for i in 0..4 {
                for j in 0..4 {
                    m[(2 * i, 2 * j)] += e.mass_per_length * l * w * s[i] * s[j];
                    k[(2 * i, 2 * j)] += e.bending_rigidity * l * w * sxx[i] * sxx[j];
                }
            }
        }
        let mc = e.mass_matrix();
        let kc = e.bending_stiffness();
        for i in 0..4 {
            for j in 0..4 {
                assert!((mc[(2 * i, 2 * j)] - m[(2 * i, 2 * j)]).abs() < 1e-15);
                assert!((kc[(2 * i, 2 * j)] - k[(2 * i, 2 * j)]).abs() < 1e-9 * kc.amax());
            }
        }
    }

    /// The tangent is the derivative of the force: central differences agree to 1e-7 relative.
    #[test]
    fn axial_tangent_is_derivative_of_force() {
        let e = el();
        let u =
            ElementVector::from_column_slice(&[0.0, 0.0, 0.01, -0.05, 1e-4, -0.02, -0.003, -0.1]);
        let (_, k) = e.axial_force_and_tangent(&u);
        for j in 0..8 {
            let h = 1e-6;
            let mut up = u;
            up[j] += h;
            let mut um = u;
            um[j] -= h;
            let fd =
                (e.axial_force_and_tangent(&up).0 - e.axial_force_and_tangent(&um).0) / (2.0 * h);
            for i in 0..8 {
                assert!(
                    (fd[i] - k[(i, j)]).abs() < 1e-6 * k.amax(),
                    "({i},{j}) {} vs {}",
                    fd[i],
                    k[(i, j)]
                );
            }
        }
    }

    /// The kept quadrature's energy is the element's (same points and weights, the weight
    /// folded into one product: rounding only) at a stretched, bent state and at rest.
    #[test]
    fn quadrature_energy_equals_element_energy() {
        let e = el();
        let q = e.axial_quadrature();
        let u =
            ElementVector::from_column_slice(&[0.0, 0.0, 0.01, -0.05, 1e-4, -0.02, -0.003, -0.1]);
        let (a, b) = (q.energy(&u), e.axial_energy(&u));
        assert!(b > 0.0 && (a - b).abs() <= 1e-14 * b, "{a} vs {b}");
        assert_eq!(q.energy(&ElementVector::zeros()), 0.0);
    }

    /// The force is the gradient of the energy.
    #[test]
    fn axial_force_is_gradient_of_energy() {
        let e = el();
        let u =
            ElementVector::from_column_slice(&[0.0, 1e-3, 0.01, -0.05, 1e-4, -0.02, -0.003, -0.1]);
        let (f, _) = e.axial_force_and_tangent(&u);
        for j in 0..8 {
            let h = 1e-7;
            let mut up = u;
            up[j] += h;
            let mut um = u;
            um[j] -= h;
            let fd = (e.axial_energy(&up) - e.axial_energy(&um)) / (2.0 * h);
            assert!((fd - f[j]).abs() < 1e-6 * f.amax().max(1.0));
        }
    }

    /// A rigid rotation of the reference by angle a has zero strain (ANCF describes rigid
    /// motion exactly), and in f32 the strain of a tiny stretch is kept (no cancellation).
    #[test]
    fn rigid_rotation_is_strain_free_and_f32_keeps_small_strain() {
        let e = el();
        let a: f64 = 0.3;
        let (c, s) = (a.cos(), a.sin());
        let l = e.length;
        // node i at origin, node j at l; rotated: r = (c x, s x), r′ = (c, s).
        let u =
            ElementVector::from_column_slice(&[0.0, 0.0, c - 1.0, s, l * c - l, l * s, c - 1.0, s]);
        for xi in [0.0, 0.3, 1.0] {
            assert!(e.axial_strain(&u, xi).abs() < 1e-15);
        }
        let ef = Element::<f32> {
            length: 0.2,
            axial_rigidity: 8.12e6,
            bending_rigidity: 1.694,
            mass_per_length: 0.3178,
        };
        let stretch = 1e-7f32; // uniform strain 1e-7
        let u = SVector::<f32, 8>::from_column_slice(&[
            0.0,
            0.0,
            stretch,
            0.0,
            0.2 * stretch,
            0.0,
            stretch,
            0.0,
        ]);
        let eps = ef.axial_strain(&u, 0.5);
        assert!((eps - 1e-7).abs() < 1e-12, "{eps}");
    }

    /// Gravity: the total vertical load equals the element weight.
    #[test]
    fn gravity_sums_to_weight() {
        let e = el();
        let q = e.gravity_force(9.81);
        assert!((q[1] + q[5] + e.mass() * 9.81).abs() < 1e-15);
    }
}

/// The 2×2 blocks of an element's axial tangent `K_l`: `(xx, xy, yy)` of block `(i, j)` for
/// `j ≥ i` (the others by symmetry; those entries are zero).
pub type TangentBlocks<T> = [[[T; 3]; 4]; 4];

/// The axial force and tangent of one element at the 5 Gauss points, with the shape
/// derivatives and weights converted to the scalar once (at construction, not per step).
///
/// At Gauss point p (weight `w_p = EA l ω_p`), with `d = S_x u`, `r′ = (1 + d₁, d₂)` and
/// `ε = d₁ + ½|d|²` (eq. 11): `Q_l = Σ_p w_p ε (s_x ⊗ r′)` and, since `S_xᵀ r′ = s_x ⊗ r′`,
/// `K_l = Σ_p w_p (s_x s_xᵀ) ⊗ (r′ r′ᵀ + ε I₂)` — a Kronecker form: each 2×2 block `(i, j)` is
/// `Σ_p w_p s_{x,i} s_{x,j} R_p` with the symmetric `R_p = r′r′ᵀ + ε I₂`. Evaluated so, the
/// tangent costs 10 × 3 products per point instead of the 64 + 32 of the dense form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxialQuadrature<T> {
    /// `∂s_k/∂x` at each Gauss point.
    pub sx: [[T; 4]; 5],
    /// `EA · l · ω_p` \[N·m\].
    pub weight: [T; 5],
}

impl<T: Real> AxialQuadrature<T> {
    /// `(d, ε)` at Gauss point `sx`: `d = S_x u − (1, 0)`… i.e. `r′ − (1, 0)`, and the strain.
    #[inline]
    fn strain(sx: &[T; 4], u: &ElementVector<T>) -> (T, T, T) {
        let (mut d1, mut d2) = (T::zero(), T::zero());
        for (pair, s) in u.as_slice().chunks_exact(2).zip(sx.iter()) {
            if let [x, y] = pair {
                d1 += *x * *s;
                d2 += *y * *s;
            }
        }
        let eps = d1 + lit::<T>(0.5) * (d1 * d1 + d2 * d2);
        (d1, d2, eps)
    }

    /// Axial elastic force `Q_l` (eqs. 12–13).
    pub fn force(&self, u: &ElementVector<T>) -> ElementVector<T> {
        let mut f = ElementVector::zeros();
        for (sx, w) in self.sx.iter().zip(self.weight.iter()) {
            let (d1, d2, eps) = Self::strain(sx, u);
            let c = *w * eps;
            let (r1, r2) = ((T::one() + d1) * c, d2 * c);
            for (pair, s) in f.as_mut_slice().chunks_exact_mut(2).zip(sx.iter()) {
                if let [fx, fy] = pair {
                    *fx += *s * r1;
                    *fy += *s * r2;
                }
            }
        }
        f
    }

    /// Axial strain energy `Σ_p ½ (EA l ω_p) ε_p²` \[J\]: [`Element::axial_energy`] from the
    /// kept shape-function derivatives (the same quadrature).
    pub fn energy(&self, u: &ElementVector<T>) -> T {
        let mut e = T::zero();
        for (sx, w) in self.sx.iter().zip(self.weight.iter()) {
            let (_, _, eps) = Self::strain(sx, u);
            e += lit::<T>(0.5) * *w * eps * eps;
        }
        e
    }

    /// Axial force `Q_l` and the 2×2 blocks of its tangent `K_l`: `blocks[i][j] = (xx, xy, yy)`
    /// of block `(i, j)` for `j ≥ i` (the others by symmetry).
    ///
    /// Two passes: the force and each point's `w_p R_p` first, then each block summed over the
    /// points in one set of three accumulators (the same sums, in the same order, as one pass
    /// over the points adding into all thirty entries — which the M4 cannot keep in registers).
    #[inline]
    fn force_and_blocks(&self, u: &ElementVector<T>) -> (ElementVector<T>, TangentBlocks<T>) {
        let mut f = ElementVector::zeros();
        let mut rr = [[T::zero(); 3]; 5];
        for ((sx, w), rr_p) in self.sx.iter().zip(self.weight.iter()).zip(rr.iter_mut()) {
            let (d1, d2, eps) = Self::strain(sx, u);
            let (r1, r2) = (T::one() + d1, d2);
            let c = *w * eps;
            for (pair, s) in f.as_mut_slice().chunks_exact_mut(2).zip(sx.iter()) {
                if let [fx, fy] = pair {
                    *fx += *s * (r1 * c);
                    *fy += *s * (r2 * c);
                }
            }
            *rr_p = [*w * (r1 * r1 + eps), *w * (r1 * r2), *w * (r2 * r2 + eps)];
        }
        // Built in place (no zeroed array first), every block by the same inlined sum with
        // constant indices: straight-line code on every target. The blocks below the diagonal
        // stay zero and are never read.
        let b = |i: usize, j: usize| Self::block_sum(&self.sx, &rr, i, j);
        let z = [T::zero(); 3];
        let blocks = [
            [b(0, 0), b(0, 1), b(0, 2), b(0, 3)],
            [z, b(1, 1), b(1, 2), b(1, 3)],
            [z, z, b(2, 2), b(2, 3)],
            [z, z, z, b(3, 3)],
        ];
        (f, blocks)
    }

    /// Block `(i, j)` of the axial tangent, `Σ_p S_i S_j w_p R_p` as `(xx, xy, yy)`, summed over
    /// the Gauss points in order (`rr[p] = w_p R_p`).
    #[inline(always)]
    fn block_sum(sx: &[[T; 4]; 5], rr: &[[T; 3]; 5], i: usize, j: usize) -> [T; 3] {
        let mut acc = [T::zero(); 3];
        for (sx, rr_p) in sx.iter().zip(rr.iter()) {
            let (Some(si), Some(sj)) = (sx.get(i), sx.get(j)) else {
                continue;
            };
            let sij = *si * *sj;
            for (b, r) in acc.iter_mut().zip(rr_p.iter()) {
                *b += sij * *r;
            }
        }
        acc
    }

    /// Axial force `Q_l` and its tangent `K_l`, whose entries are handed to `put(row, col,
    /// value)` (local rows/columns 0..8, every entry of the symmetric matrix once).
    pub fn tangent(
        &self,
        u: &ElementVector<T>,
        mut put: impl FnMut(usize, usize, T),
    ) -> ElementVector<T> {
        let (f, blocks) = self.force_and_blocks(u);
        for (i, row) in blocks.iter().enumerate() {
            for (j, [xx, xy, yy]) in row.iter().enumerate().skip(i) {
                let (r, c) = (2 * i, 2 * j);
                put(r, c, *xx);
                put(r, c + 1, *xy);
                put(r + 1, c, *xy);
                put(r + 1, c + 1, *yy);
                if j != i {
                    put(c, r, *xx);
                    put(c + 1, r, *xy);
                    put(c, r + 1, *xy);
                    put(c + 1, r + 1, *yy);
                }
            }
        }
        f
    }

    /// Axial force `Q_l`, and the element's 8×8 Newton block written into `block`:
    /// `linear ⊗ I₂ + scale · K_l` (`linear` = the 4×4 `c_m M₄ + c_k K₄`; rows of the element's
    /// local coordinates). The step path's form of [`AxialQuadrature::tangent`]: every entry
    /// written once, `(linear or 0) + scale · K_l`.
    #[inline(always)]
    pub fn tangent_block(
        &self,
        u: &ElementVector<T>,
        linear: &[[T; 4]; 4],
        scale: T,
        block: &mut [[T; 8]; 8],
    ) -> ElementVector<T> {
        self.tangent_block_with(u, linear, scale, block).0
    }

    /// [`AxialQuadrature::tangent_block`], also returning `K_l`'s 2×2 blocks as computed
    /// (`(xx, xy, yy)` of block `(i, j)` for `j ≥ i`): what another product of the same
    /// tangent needs (the estimator's root-stress gradient), without a second quadrature.
    #[inline(always)]
    pub fn tangent_block_with(
        &self,
        u: &ElementVector<T>,
        linear: &[[T; 4]; 4],
        scale: T,
        block: &mut [[T; 8]; 8],
    ) -> (ElementVector<T>, TangentBlocks<T>) {
        let (f, blocks) = self.force_and_blocks(u);
        let zero = T::zero();
        // Block (i, j) with j < i is block (j, i) transposed; a 2×2 block is symmetric itself.
        for (i, (rows, lin)) in block.chunks_exact_mut(2).zip(linear.iter()).enumerate() {
            let [row_x, row_y] = rows else {
                continue;
            };
            let pairs = row_x.chunks_exact_mut(2).zip(row_y.chunks_exact_mut(2));
            for (j, ((px, py), l)) in pairs.zip(lin.iter()).enumerate() {
                let (a, b) = if j >= i { (i, j) } else { (j, i) };
                if let (Some([xx, xy, yy]), [x0, x1], [y0, y1]) =
                    (blocks.get(a).and_then(|r| r.get(b)), px, py)
                {
                    *x0 = *l + scale * *xx;
                    *x1 = zero + scale * *xy;
                    *y0 = zero + scale * *xy;
                    *y1 = *l + scale * *yy;
                }
            }
        }
        (f, blocks)
    }
}
