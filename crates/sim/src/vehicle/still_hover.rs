//! The still hover of a flown body: the one set of steady rotor speeds that holds its weight
//! with no moment, and the power it costs. It is the floor of the mean power of any flight that
//! stays in place: rotor power is convex in each rotor's Ω² (k_M Ω³ = k_M (Ω²)^{3/2}) and over
//! a long hold the mean vertical thrust must equal the weight and the mean moments must vanish,
//! so by Jensen's inequality no sequence of commands averages below the constant solution.
//!
//! The floor belongs to the body as flown, per-rotor thrust mismatch and model error included:
//! a rotor that makes more thrust at a given speed (at the same hub moment) holds its share more
//! cheaply, so two seeds of the same airframe hover at different powers.

use crate::vehicle::dynamics::Dynamics;
use crate::vehicle::power::{power, PowerSplit};
use crate::vehicle::VehicleParams;

/// A body's still hover.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StillHover {
    /// The weight the rotors carry, N.
    pub weight_n: f64,
    /// Each rotor's speed, rad/s.
    pub rotor_speed: [f64; 4],
    pub power: PowerSplit,
}

impl StillHover {
    /// The still hover of `dynamics`'s body with `p`'s motor, ESC and avionics power model;
    /// `None` when no set of non-negative rotor speeds holds it still (a layout that cannot
    /// balance its moments).
    pub fn of(p: &VehicleParams, dynamics: &Dynamics) -> Option<Self> {
        let (rows, weight_n) = dynamics.hover_rows();
        let x = solve4(rows, [weight_n, 0.0, 0.0, 0.0])?;
        // NaN too: a singular system that slipped past the pivot test is no hover.
        if !x.iter().all(|&xi| xi.is_finite() && xi >= 0.0) {
            return None;
        }
        let rotor_speed = x.map(f64::sqrt);
        Some(Self {
            weight_n,
            rotor_speed,
            power: power(p, &rotor_speed, &[0.0; 4]),
        })
    }

    /// Power of the balanced split scaled to carry `thrust_n` instead of the weight, W: every
    /// Ω² scales with the thrust, so the motors' share grows as thrust^{3/2} and the ESCs'
    /// quiescent draw and the avionics stay.
    pub fn total_w_at(&self, p: &VehicleParams, thrust_n: f64) -> f64 {
        let ratio = (thrust_n / self.weight_n).max(0.0);
        let motors_w = self.power.motors_w * ratio * ratio.sqrt();
        self.power.total_w() + (motors_w - self.power.motors_w) * (1.0 + p.esc_loss_fraction)
    }
}

/// Solves the 4x4 system `a x = b` by Gaussian elimination with partial pivoting; `None` when
/// `a` is singular.
fn solve4(mut a: [[f64; 4]; 4], mut b: [f64; 4]) -> Option<[f64; 4]> {
    let scale = a.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    for col in 0..4 {
        let pivot = (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() <= 1e-12 * scale {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let b_col = b[col];
        let (above, below) = a.split_at_mut(col + 1);
        let pivot_row = &above[col];
        for (row, rhs) in below.iter_mut().zip(&mut b[col + 1..]) {
            let f = row[col] / pivot_row[col];
            for (r, p) in row.iter_mut().zip(pivot_row).skip(col) {
                *r -= f * p;
            }
            *rhs -= f * b_col;
        }
    }
    let mut x = [0.0; 4];
    for row in (0..4).rev() {
        let tail: f64 = (row + 1..4).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - tail) / a[row][row];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::model_error::{ModelError, WeakMotor};

    #[test]
    fn the_nominal_body_hovers_at_the_nominal_speed() {
        for p in [VehicleParams::f450(), VehicleParams::pelican()] {
            let d = Dynamics::new(&p, [1.0; 4], 1e-3);
            let h = StillHover::of(&p, &d).unwrap();
            let w = p.hover_rotor_speed();
            assert!(
                h.rotor_speed.iter().all(|s| (s - w).abs() < 1e-9 * w),
                "{h:?}"
            );
            let nominal = power(&p, &[w; 4], &[0.0; 4]).total_w();
            assert!((h.power.total_w() - nominal).abs() < 1e-9 * nominal);
            assert!((h.total_w_at(&p, h.weight_n) - nominal).abs() < 1e-9 * nominal);
        }
    }

    #[test]
    fn the_solution_balances_the_body_and_mismatch_moves_the_floor() {
        let p = VehicleParams::f450();
        let nominal = StillHover::of(&p, &Dynamics::new(&p, [1.0; 4], 1e-3)).unwrap();
        // Stronger rotors hold the same weight at lower speed and power; weaker ones cost more.
        for (m, cheaper) in [([1.02, 1.0, 1.03, 1.01], true), ([0.97; 4], false)] {
            let d = Dynamics::new(&p, m, 1e-3);
            let h = StillHover::of(&p, &d).unwrap();
            let (rows, weight) = d.hover_rows();
            let x = h.rotor_speed.map(|s| s * s);
            let residual: Vec<f64> = rows
                .iter()
                .map(|r| r.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>())
                .collect();
            assert!((residual[0] - weight).abs() < 1e-9 * weight, "{residual:?}");
            assert!(residual[1..].iter().all(|r| r.abs() < 1e-9), "{residual:?}");
            assert_eq!(
                h.power.total_w() < nominal.power.total_w(),
                cheaper,
                "{m:?}"
            );
        }
        // A weak motor on a heavier body: still balanced, and dearer than the nominal hover.
        let error = ModelError {
            mass_scale: 1.2,
            weak_motor: Some(WeakMotor {
                index: 1,
                factor: 0.8,
            }),
            ..ModelError::NONE
        };
        let d = Dynamics::with_body(&p, &error.body(&p, true), [1.0; 4], 1e-3);
        let h = StillHover::of(&p, &d).unwrap();
        assert!(h.power.total_w() > nominal.power.total_w());
        assert!((h.weight_n - 1.2 * nominal.weight_n).abs() < 1e-9);
    }

    #[test]
    fn a_singular_layout_has_no_still_hover() {
        let p = VehicleParams {
            moment_coeff: 0.0,
            ..VehicleParams::f450()
        };
        // Without hub moments the yaw row is zero: no unique balanced split.
        assert_eq!(StillHover::of(&p, &Dynamics::new(&p, [1.0; 4], 1e-3)), None);
    }
}
