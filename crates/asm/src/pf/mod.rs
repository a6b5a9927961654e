//! The I-ASM particle filter over candidate source positions.
//!
//! Each particle is a hypothesis of one source's position (world frame, m). Particles
//! start on the map's known cells, drift by a small random walk (the sources are static;
//! the walk keeps the cloud from collapsing onto one cell), and are weighted by how well
//! their bearing from the robot matches the nearest DoA, with a floor so that one missed
//! or false DoA cannot wipe a hypothesis out, and a distance penalty against far ghosts.

mod resample;

use rand::Rng;
use rand::seq::index::sample;
use rand_distr::StandardNormal;

pub use resample::low_variance;

/// The I-ASM likelihood of a particle given the DoAs of one stop.
///
/// With `f` the zero-mean normal density of standard deviation `sigma` (rad):
/// `L = max(lambda, f(dtheta) exp(-d / beta))`, `lambda = f(2 sigma)`, where `dtheta` is the
/// smallest wrapped angle between the particle's bearing and a DoA, and `d` the particle's
/// distance from the robot (as the authors coded it; without `beta`, the paper's WDP
/// variant, the exponential is dropped).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Likelihood {
    inv_two_var: f64,
    norm: f64,
    floor: f64,
    inv_beta: f64,
    /// `cos(2 sigma)`: beyond this angular mismatch the likelihood is the floor.
    gate_cos: f64,
}

impl Likelihood {
    /// `sigma` in radians, `beta` in metres (`None`: no distance penalty).
    pub fn new(sigma: f64, beta: Option<f64>) -> Self {
        let norm = 1.0 / (sigma * (2.0 * std::f64::consts::PI).sqrt());
        let inv_two_var = 1.0 / (2.0 * sigma * sigma);
        Self {
            inv_two_var,
            norm,
            floor: norm * (-4.0f64 * sigma * sigma * inv_two_var).exp(),
            inv_beta: beta.map_or(0.0, |b| 1.0 / b),
            gate_cos: (2.0 * sigma).min(std::f64::consts::PI).cos(),
        }
    }

    /// The floor `lambda = f(2 sigma)`.
    pub fn floor(&self) -> f64 {
        self.floor
    }

    /// The likelihood for angular mismatch `dtheta` (rad, `>= 0`) at distance `d` (m).
    pub fn eval(&self, dtheta: f64, d: f64) -> f64 {
        // f(dtheta) exp(-d / beta) in one exponential.
        (self.norm * (-dtheta * dtheta * self.inv_two_var - d * self.inv_beta).exp())
            .max(self.floor)
    }
}

/// A weighted particle set.
#[derive(Clone, Debug, PartialEq)]
pub struct ParticleFilter {
    particles: Vec<[f64; 2]>,
    weights: Vec<f64>,
}

impl ParticleFilter {
    /// `m` particles drawn without replacement from `cells` (cell centres), equal weights.
    ///
    /// # Panics
    /// If `m` is 0 or exceeds `cells.len()`.
    pub fn from_cells(cells: &[[f64; 2]], m: usize, rng: &mut impl Rng) -> Self {
        assert!(m > 0 && m <= cells.len(), "0 < M <= cells");
        let particles: Vec<[f64; 2]> = sample(rng, cells.len(), m)
            .into_iter()
            .map(|i| cells[i])
            .collect();
        Self {
            weights: vec![1.0 / m as f64; m],
            particles,
        }
    }

    /// A filter from explicit particles and weights (normalised here).
    ///
    /// # Panics
    /// If the lengths differ, the set is empty, or the weights do not sum to a positive number.
    pub fn from_parts(particles: Vec<[f64; 2]>, mut weights: Vec<f64>) -> Self {
        assert!(!particles.is_empty() && particles.len() == weights.len());
        let s: f64 = weights.iter().sum();
        assert!(s > 0.0, "positive total weight");
        weights.iter_mut().for_each(|w| *w /= s);
        Self { particles, weights }
    }

    /// Particle positions (m).
    pub fn particles(&self) -> &[[f64; 2]] {
        &self.particles
    }

    /// Normalised weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Random-walk state update: every coordinate moves by `N(0, sigma_p^2)`.
    ///
    /// # Panics
    /// If `sigma_p` is negative or not finite (`IasmConfig::validate` refuses both).
    pub fn predict(&mut self, sigma_p: f64, rng: &mut impl Rng) {
        assert!(
            sigma_p.is_finite() && sigma_p >= 0.0,
            "sigma_p must be finite and non-negative"
        );
        // `sigma_p z` for standard normal `z`: the numbers `Normal::new(0, sigma_p)` draws
        // (it adds its mean, 0, to them), without a call per draw.
        for p in &mut self.particles {
            p[0] += sigma_p * rng.sample::<f64, _>(StandardNormal);
            p[1] += sigma_p * rng.sample::<f64, _>(StandardNormal);
        }
    }

    /// Weight update with the DoAs (world bearings, rad) seen from `robot`; a stop with no
    /// DoA left carries no information and changes nothing. Returns the effective sample
    /// size after it ([`ParticleFilter::neff`]), found in the normalising pass.
    ///
    /// This is the filter's hot loop (particles x stops x rounds). A particle more than
    /// `2 sigma` from every DoA gets the floor whatever its distance, and most particles
    /// are such: they are recognised with one dot product per DoA (`cos(dtheta) <=
    /// cos(2 sigma)`), and only the rest pay for an `atan2` and an `exp`.
    pub fn update(&mut self, robot: [f64; 2], bearings: &[f64], lik: &Likelihood) -> f64 {
        if bearings.is_empty() {
            return self.neff();
        }
        let dirs: Vec<(f64, f64)> = bearings.iter().map(|b| (b.cos(), b.sin())).collect();
        let mut total = 0.0;
        for (p, w) in self.particles.iter().zip(self.weights.iter_mut()) {
            let (dx, dy) = (p[0] - robot[0], p[1] - robot[1]);
            let d = (dx * dx + dy * dy).sqrt();
            // d cos(dtheta) for the nearest DoA: the largest projection.
            let (mut dot, mut cross) = (f64::NEG_INFINITY, 0.0);
            for &(c, s) in &dirs {
                let v = dx * c + dy * s;
                if v > dot {
                    dot = v;
                    cross = dx * s - dy * c;
                }
            }
            let l = if dot <= d * lik.gate_cos {
                lik.floor
            } else {
                lik.eval(cross.abs().atan2(dot), d)
            };
            *w *= l;
            total += *w;
        }
        self.normalise(total)
    }

    /// Divides the weights by their `total` (if every weight underflowed, no particle is
    /// preferred) and returns the effective sample size of the weights it leaves, summed
    /// in the same pass ([`ParticleFilter::neff`] to the last bit: the same squares, added
    /// in the same order).
    fn normalise(&mut self, total: f64) -> f64 {
        let mut squares = 0.0;
        if total > 0.0 && total.is_finite() {
            for w in &mut self.weights {
                *w /= total;
                squares += *w * *w;
            }
        } else {
            // Every weight underflowed: no particle is preferred.
            let u = 1.0 / self.weights.len() as f64;
            for w in &mut self.weights {
                *w = u;
                squares += u * u;
            }
        }
        1.0 / squares
    }

    /// [`ParticleFilter::update`] with a gain per DoA (`gains[j]` for `bearings[j]`, in
    /// `(0, 1]`): the DoA is a source with probability `g` and clutter otherwise, so its
    /// likelihood is the mixture `lambda + g (L - lambda)` of the paper's `L = max(lambda,
    /// f(dtheta) exp(-d / beta))` and the floor `lambda` (clutter explains any bearing
    /// alike), and a particle takes the largest over the DoAs. A DoA of gain `g` lifts a
    /// particle above the floor `g` times as far as one of gain 1, and never below it
    /// (see `IasmConfig::rank_gain`). With every gain 1 it is the paper's update. Returns
    /// the effective sample size after it, as [`ParticleFilter::update`].
    ///
    /// # Panics
    /// If `gains` and `bearings` differ in length.
    pub fn update_gained(
        &mut self,
        robot: [f64; 2],
        bearings: &[f64],
        gains: &[f64],
        lik: &Likelihood,
    ) -> f64 {
        assert_eq!(bearings.len(), gains.len(), "one gain per DoA");
        if bearings.is_empty() {
            return self.neff();
        }
        let dirs: Vec<(f64, f64, f64)> = bearings
            .iter()
            .zip(gains)
            .map(|(b, &g)| (b.cos(), b.sin(), g))
            .collect();
        let floor = lik.floor;
        let mut total = 0.0;
        for (p, w) in self.particles.iter().zip(self.weights.iter_mut()) {
            let (dx, dy) = (p[0] - robot[0], p[1] - robot[1]);
            let d = (dx * dx + dy * dy).sqrt();
            let gate = d * lik.gate_cos;
            // Only the DoAs within `2 sigma` of the particle's bearing can lift it off the
            // floor: one dot product each tells them.
            let mut l = floor;
            for &(c, s, g) in &dirs {
                let dot = dx * c + dy * s;
                if dot > gate {
                    let cross = dx * s - dy * c;
                    l = l.max(floor + g * (lik.eval(cross.abs().atan2(dot), d) - floor));
                }
            }
            *w *= l;
            total += *w;
        }
        self.normalise(total)
    }

    /// The effective sample size `1 / sum w^2`, in `[1, M]`.
    pub fn neff(&self) -> f64 {
        1.0 / self.weights.iter().map(|w| w * w).sum::<f64>()
    }

    /// Low-variance resampling; weights become equal.
    pub fn resample(&mut self, rng: &mut impl Rng) {
        let idx = low_variance(&self.weights, rng);
        self.particles = idx.iter().map(|&i| self.particles[i]).collect();
        let m = self.particles.len();
        self.weights = vec![1.0 / m as f64; m];
    }

    /// The largest eigenvalue (m^2) of the particles' unweighted sample covariance: the
    /// cloud's spread along its widest direction.
    pub fn max_cov_eigenvalue(&self) -> f64 {
        let c = covariance(&self.particles);
        max_eigenvalue(c)
    }

    /// The weighted mean position (the WS variant's estimate).
    pub fn weighted_mean(&self) -> [f64; 2] {
        let mut m = [0.0; 2];
        for (p, w) in self.particles.iter().zip(&self.weights) {
            m[0] += w * p[0];
            m[1] += w * p[1];
        }
        m
    }
}

/// Mean of points.
pub fn mean(points: &[[f64; 2]]) -> [f64; 2] {
    let n = points.len().max(1) as f64;
    let s = points
        .iter()
        .fold([0.0; 2], |a, p| [a[0] + p[0], a[1] + p[1]]);
    [s[0] / n, s[1] / n]
}

/// Unbiased sample covariance `[[xx, xy], [xy, yy]]` of points (0 for fewer than two).
pub fn covariance(points: &[[f64; 2]]) -> [[f64; 2]; 2] {
    if points.len() < 2 {
        return [[0.0; 2]; 2];
    }
    let m = mean(points);
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for p in points {
        let (dx, dy) = (p[0] - m[0], p[1] - m[1]);
        xx += dx * dx;
        xy += dx * dy;
        yy += dy * dy;
    }
    let k = 1.0 / (points.len() - 1) as f64;
    [[xx * k, xy * k], [xy * k, yy * k]]
}

/// The larger eigenvalue of a symmetric 2 x 2 matrix.
pub fn max_eigenvalue(c: [[f64; 2]; 2]) -> f64 {
    let (a, b, d) = (c[0][0], c[0][1], c[1][1]);
    0.5 * (a + d) + (0.25 * (a - d) * (a - d) + b * b).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use rand::{SeedableRng, rngs::StdRng};

    const SEED: u64 = 5;

    #[test]
    fn likelihood_matches_hand_computed_values() {
        let sigma = 5f64.to_radians();
        let l = Likelihood::new(sigma, Some(2.5));
        let f = |x: f64| {
            (-x * x / (2.0 * sigma * sigma)).exp() / (sigma * (2.0 * std::f64::consts::PI).sqrt())
        };
        // On the DoA, 1 m away: f(0) e^{-0.4}.
        assert_abs_diff_eq!(l.eval(0.0, 1.0), f(0.0) * (-0.4f64).exp(), epsilon = 1e-12);
        // The floor is f(2 sigma) = f(0) e^{-2}.
        assert_abs_diff_eq!(l.floor(), f(0.0) * (-2.0f64).exp(), epsilon = 1e-12);
        // Far off the DoA: the floor.
        assert_eq!(l.eval(0.5, 1.0), l.floor());
        // On the DoA but 10 m away: f(0) e^{-4} < f(2 sigma): the floor again.
        assert_eq!(l.eval(0.0, 10.0), l.floor());
        // WDP: no distance term.
        let w = Likelihood::new(sigma, None);
        assert_abs_diff_eq!(w.eval(sigma, 50.0), f(sigma), epsilon = 1e-12);
    }

    #[test]
    fn weights_follow_the_nearest_doa() {
        // Robot at the origin; DoAs towards +x and +y. Particles on +x (1 m), on +y (2 m),
        // and at -x (1 m, no DoA).
        let mut pf =
            ParticleFilter::from_parts(vec![[1.0, 0.0], [0.0, 2.0], [-1.0, 0.0]], vec![1.0; 3]);
        let sigma = 5f64.to_radians();
        let l = Likelihood::new(sigma, Some(2.5));
        pf.update([0.0, 0.0], &[0.0, std::f64::consts::FRAC_PI_2], &l);
        let raw = [l.eval(0.0, 1.0), l.eval(0.0, 2.0), l.floor()];
        let s: f64 = raw.iter().sum();
        for (w, r) in pf.weights().iter().zip(raw) {
            assert_abs_diff_eq!(*w, r / s, epsilon = 1e-12);
        }
        assert_abs_diff_eq!(pf.weights().iter().sum::<f64>(), 1.0, epsilon = 1e-12);
    }

    #[test]
    fn fast_update_matches_the_naive_formula() {
        // Oracle: atan2 of each particle, wrapped difference to every DoA, min, eval.
        use crate::wrap_rad;
        use rand::Rng;
        let mut rng = StdRng::seed_from_u64(SEED);
        let pts: Vec<[f64; 2]> = (0..2000)
            .map(|_| [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)])
            .collect();
        let bearings = [3.0, -2.9, 0.4, 1.7];
        let robot = [0.3, -0.2];
        let l = Likelihood::new(5f64.to_radians(), Some(2.5));
        let mut pf = ParticleFilter::from_parts(pts.clone(), vec![1.0; pts.len()]);
        pf.update(robot, &bearings, &l);
        let raw: Vec<f64> = pts
            .iter()
            .map(|p| {
                let (dx, dy) = (p[0] - robot[0], p[1] - robot[1]);
                let th = dy.atan2(dx);
                let dt = bearings
                    .iter()
                    .map(|&b| wrap_rad(th - b).abs())
                    .fold(f64::INFINITY, f64::min);
                l.eval(dt, dx.hypot(dy))
            })
            .collect();
        let s: f64 = raw.iter().sum();
        for (w, r) in pf.weights().iter().zip(&raw) {
            assert_abs_diff_eq!(*w, r / s, epsilon = 1e-12);
        }
        assert!(
            raw.iter().filter(|&&r| r > l.floor()).count() > 20,
            "some particles above the floor"
        );
    }

    /// The updates return the effective sample size of the weights they leave, to the
    /// last bit of `neff()` (the resampling test compares it with a threshold): after a
    /// normal update, after a gained one, after one whose weights have all underflowed,
    /// and after a stop with no DoA.
    #[test]
    fn updates_return_the_effective_sample_size_of_their_weights() {
        use rand::Rng;
        let mut rng = StdRng::seed_from_u64(SEED);
        let pts: Vec<[f64; 2]> = (0..1500)
            .map(|_| [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)])
            .collect();
        let l = Likelihood::new(5f64.to_radians(), Some(2.5));
        let mut pf = ParticleFilter::from_parts(pts.clone(), vec![1.0; pts.len()]);
        let n = pf.update([0.3, -0.2], &[3.0, -2.9, 0.4, 1.7], &l);
        assert_eq!(n.to_bits(), pf.neff().to_bits());
        assert!(n > 1.0 && n < pts.len() as f64, "{n}");
        let gains = [1.0, 0.5, 0.25];
        let n = pf.update_gained([1.0, 1.0], &[0.1, 2.0, -1.0], &gains, &l);
        assert_eq!(n.to_bits(), pf.neff().to_bits());
        // Every weight underflowed to 0 before the stop: the total is 0, and the filter
        // falls back to equal weights, whose effective size is M.
        let mut tiny = ParticleFilter::from_parts(pts.clone(), vec![1.0; pts.len()]);
        tiny.weights.iter_mut().for_each(|w| *w = 0.0);
        let n = tiny.update([0.0, 0.0], &[0.0], &l);
        assert_eq!(n.to_bits(), tiny.neff().to_bits());
        assert!((n - pts.len() as f64).abs() < 1e-6, "{n}");
        // No DoA: nothing changes, and the size is the weights' as they stand.
        let before = pf.neff();
        assert_eq!(pf.update([0.0, 0.0], &[], &l).to_bits(), before.to_bits());
    }

    #[test]
    fn a_gained_doa_lifts_a_particle_above_the_floor_by_its_gain() {
        // Robot at the origin; DoAs towards +x (gain 1) and +y (gain 0.5). Particles on +x
        // (1 m), on +y (1 m), 3 degrees off +y (2 m), and at -x (no DoA): the floor plus
        // the gain times what the paper's likelihood lifts them above it.
        let sigma = 5f64.to_radians();
        let l = Likelihood::new(sigma, Some(2.5));
        let off = 93f64.to_radians();
        let pts = vec![
            [1.0, 0.0],
            [0.0, 1.0],
            [2.0 * off.cos(), 2.0 * off.sin()],
            [-1.0, 0.0],
        ];
        let mut pf = ParticleFilter::from_parts(pts.clone(), vec![1.0; 4]);
        pf.update_gained(
            [0.0, 0.0],
            &[0.0, std::f64::consts::FRAC_PI_2],
            &[1.0, 0.5],
            &l,
        );
        let lam = l.floor();
        let raw = [
            l.eval(0.0, 1.0),
            lam + 0.5 * (l.eval(0.0, 1.0) - lam),
            lam + 0.5 * (l.eval(3f64.to_radians(), 2.0) - lam),
            lam,
        ];
        let s: f64 = raw.iter().sum();
        for (w, r) in pf.weights().iter().zip(raw) {
            assert_abs_diff_eq!(*w, r / s, epsilon = 1e-12);
        }
        // Every gain 1: the paper's update.
        // Two of the three DoAs within 3 degrees of a particle's bearing.
        let bearings = [0.25, 1.6, -2.0];
        let mut a = ParticleFilter::from_parts(pts.clone(), vec![1.0; 4]);
        let mut b = ParticleFilter::from_parts(pts, vec![1.0; 4]);
        a.update([0.1, -0.2], &bearings, &l);
        b.update_gained([0.1, -0.2], &bearings, &[1.0; 3], &l);
        for (x, y) in a.weights().iter().zip(b.weights()) {
            assert_abs_diff_eq!(*x, *y, epsilon = 1e-15);
        }
    }

    #[test]
    fn bearings_wrap_across_pi() {
        // A particle at bearing 179 degrees is 2 degrees from a DoA at -179 degrees.
        let mut pf = ParticleFilter::from_parts(
            vec![[-1.0, 1f64.to_radians().tan()], [0.0, -1.0]],
            vec![1.0; 2],
        );
        let l = Likelihood::new(5f64.to_radians(), None);
        pf.update([0.0, 0.0], &[-179f64.to_radians()], &l);
        // Wrapped, the first is 2 degrees off: f(2) against the floor f(10) of the second,
        // a ratio of exp((10^2 - 2^2) / (2 * 5^2)); unwrapped, both would sit on the floor.
        let ratio = pf.weights()[0] / pf.weights()[1];
        assert_abs_diff_eq!(ratio, (96.0f64 / 50.0).exp(), epsilon = 1e-9);
    }

    #[test]
    fn covariance_eigenvalue_of_a_line() {
        // Points on y = x, spread 1 in x: variance along the diagonal is 2 * var(x).
        let pts: Vec<[f64; 2]> = (0..5).map(|i| [i as f64, i as f64]).collect();
        let c = covariance(&pts);
        assert_abs_diff_eq!(c[0][0], 2.5, epsilon = 1e-12);
        assert_abs_diff_eq!(max_eigenvalue(c), 5.0, epsilon = 1e-12);
    }

    #[test]
    fn resampling_keeps_m_particles_and_favours_heavy_ones() {
        let mut rng = StdRng::seed_from_u64(SEED);
        let pts: Vec<[f64; 2]> = (0..1000).map(|i| [i as f64, 0.0]).collect();
        let mut w = vec![1.0; 1000];
        w[7] = 1000.0; // half the total weight
        let mut pf = ParticleFilter::from_parts(pts, w);
        pf.resample(&mut rng);
        assert_eq!(pf.particles().len(), 1000);
        let sevens = pf.particles().iter().filter(|p| p[0] == 7.0).count();
        // Low-variance resampling gives exactly floor or ceil of M w = 500.2.
        assert!((500..=501).contains(&sevens), "{sevens}");
        assert_abs_diff_eq!(pf.neff(), 1000.0, epsilon = 1e-6);
    }

    #[test]
    fn initial_particles_are_distinct_known_cells() {
        let mut rng = StdRng::seed_from_u64(SEED);
        let cells: Vec<[f64; 2]> = (0..100).map(|i| [i as f64, 1.0]).collect();
        let pf = ParticleFilter::from_cells(&cells, 11, &mut rng);
        let mut xs: Vec<i64> = pf.particles().iter().map(|p| p[0] as i64).collect();
        xs.sort();
        xs.dedup();
        assert_eq!(xs.len(), 11);
        assert_abs_diff_eq!(pf.weights().iter().sum::<f64>(), 1.0, epsilon = 1e-12);
    }
}
