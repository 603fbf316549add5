//! Quadrotor mixer, seed 002 eq. 20 (square "X" configuration) and its plus-configuration twin.
//!
//! Eq. 20 maps collective, roll, pitch and yaw commands to motor commands
//! `x_i = sqrt(delta_T +- delta_phi +- delta_theta +- delta_psi)`: the sum under the root is the
//! motor's thrust as a fraction of its maximum, and the root turns it into a speed command because
//! rotor thrust goes with the square of speed. The signs come from each motor's position and spin
//! ([`FrameKind::motors`]); in the seed's printed eq. 20 the yaw sign of motor 1 disagrees with its
//! eq. 19 (yaw moment -M1 + M2 - M3 + M4), and eq. 19 is followed here.
//!
//! Saturation: when the request does not fit in [0, 1] per motor, roll and pitch are kept whole
//! and the collective is moved (attitude wins over collective thrust); yaw is reduced before roll
//! and pitch; only when roll and pitch alone exceed the motors' range are they scaled down
//! together, which keeps the direction of the tilting torque.

use crate::msgs::{FrameKind, MotorCommands};
use libm::{fabsf, sqrtf};

/// Collective and torque requests in normalised units: `collective` is the mean motor thrust as a
/// fraction of one motor's maximum; roll, pitch and yaw (about body FLU x, y, z) are the thrust
/// fraction added to or taken from each motor that contributes to that axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Demand {
    pub collective: f32,
    pub roll: f32,
    pub pitch: f32,
    pub yaw: f32,
}

/// The mixer's answer: commands plus what was actually delivered.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mixed {
    pub motors: MotorCommands,
    /// Per-motor thrust fractions before the square root.
    pub thrust_norm: [f32; 4],
    /// The demand these thrusts produce; equals the request when nothing saturated.
    pub achieved: Demand,
    /// True when any part of the request had to be changed to fit.
    pub saturated: bool,
}

/// Per-motor coefficients for a frame, derived from its geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mixer {
    /// Roll, pitch and yaw coefficient of each motor (each in {-1, 0, 1}).
    coef: [[f32; 3]; 4],
    /// One over the sum of squares of each axis' coefficients.
    inverse_norms: [f32; 3],
}

impl Mixer {
    pub fn new(frame: FrameKind) -> Self {
        let motors = frame.motors();
        let max_x = motors
            .iter()
            .fold(0.0f32, |m, g| m.max(fabsf(g.arm_dir[0])));
        let max_y = motors
            .iter()
            .fold(0.0f32, |m, g| m.max(fabsf(g.arm_dir[1])));
        let mut coef = [[0.0; 3]; 4];
        for (c, g) in coef.iter_mut().zip(motors.iter()) {
            // Lift on the left (+y) rolls positive about x; lift in front (+x) pitches negative
            // about y (nose up); a clockwise rotor's reaction torque yaws positive about z.
            c[0] = round_unit(g.arm_dir[1] / max_y);
            c[1] = round_unit(-g.arm_dir[0] / max_x);
            c[2] = if g.spins_ccw { -1.0 } else { 1.0 };
        }
        let inverse_norms =
            core::array::from_fn(|axis| 1.0 / coef.iter().map(|c| c[axis] * c[axis]).sum::<f32>());
        Self {
            coef,
            inverse_norms,
        }
    }

    /// Allocates a demand to the four motors (seed 002 eq. 20) with attitude-first saturation.
    /// Non-finite parts of the demand are treated as zero, so the commands are always finite.
    pub fn mix(&self, demand: Demand) -> Mixed {
        // v * 0 is 0 for finite v and NaN otherwise: cheaper than `is_finite`, every step.
        let clean = |v: f32| if v * 0.0 == 0.0 { v } else { 0.0 };
        let (mut roll, mut pitch) = (clean(demand.roll), clean(demand.pitch));
        let yaw_request = clean(demand.yaw);
        let collective_request = clean(demand.collective);

        let mut rp = [0.0; 4];
        let mut span = self.fill(&mut rp, roll, pitch, 0.0);
        // Whether any part of the request was changed to fit.
        let mut cut = span > 1.0;
        if span > 1.0 {
            roll /= span;
            pitch /= span;
            span = self.fill(&mut rp, roll, pitch, 0.0);
        }
        let mut diff = [0.0; 4];
        if self.fill(&mut diff, roll, pitch, yaw_request) > 1.0 {
            // The whole yaw request does not fit beside roll and pitch: it gives way.
            cut = true;
            let yaw = yaw_request * self.yaw_fraction(&rp, yaw_request, span);
            self.fill(&mut diff, roll, pitch, yaw);
        }
        let lowest = diff.iter().fold(f32::INFINITY, |m, &v| m.min(v));
        let highest = diff.iter().fold(f32::NEG_INFINITY, |m, &v| m.max(v));
        // Attitude wins: the collective moves to wherever the differential fits in [0, 1]. When
        // the differential spans the whole range, rounding can leave -lowest a hair above
        // 1 - highest; `clamp` would panic on that empty interval, max-then-min takes its top.
        let collective = collective_request.max(-lowest).min(1.0 - highest);
        cut |= collective != collective_request;

        let mut thrust_norm = [0.0; 4];
        let mut motors = MotorCommands::STOPPED;
        for i in 0..4 {
            thrust_norm[i] = (collective + diff[i]).clamp(0.0, 1.0);
            motors.throttle_norm[i] = sqrtf(thrust_norm[i]);
        }
        // Nothing cut from a finite request: the thrusts deliver it (to rounding), and working
        // that out every step was a fifth of the mixer. Otherwise what they deliver is compared;
        // a non-finite request never compares close, so it is reported as saturated too.
        let finite =
            demand.collective * 0.0 + demand.roll * 0.0 + demand.pitch * 0.0 + demand.yaw * 0.0
                == 0.0;
        let (achieved, saturated) = if cut || !finite {
            let achieved = self.demand_of(&thrust_norm);
            (achieved, !close(achieved, demand))
        } else {
            (demand, false)
        };
        Mixed {
            motors,
            thrust_norm,
            achieved,
            saturated,
        }
    }

    /// The collective and torques a set of per-motor thrust fractions produces (the inverse of
    /// the allocation: the coefficient columns are orthogonal, so each axis is a projection).
    pub fn demand_of(&self, thrust_norm: &[f32; 4]) -> Demand {
        let mut sums = [0.0f32; 3];
        for (c, &f) in self.coef.iter().zip(thrust_norm.iter()) {
            for axis in 0..3 {
                sums[axis] += c[axis] * f;
            }
        }
        Demand {
            collective: thrust_norm.iter().sum::<f32>() / 4.0,
            roll: sums[0] * self.inverse_norms[0],
            pitch: sums[1] * self.inverse_norms[1],
            yaw: sums[2] * self.inverse_norms[2],
        }
    }

    /// Writes each motor's differential thrust and returns the spread (max - min).
    fn fill(&self, out: &mut [f32; 4], roll: f32, pitch: f32, yaw: f32) -> f32 {
        for (o, c) in out.iter_mut().zip(self.coef.iter()) {
            *o = c[0] * roll + c[1] * pitch + c[2] * yaw;
        }
        out.iter().fold(f32::NEG_INFINITY, |m, &v| m.max(v))
            - out.iter().fold(f32::INFINITY, |m, &v| m.min(v))
    }

    /// The largest k in [0, 1] for which roll/pitch plus k times the yaw request keeps every pair
    /// of motors within a spread of 1 (so a collective exists that fits them all).
    fn yaw_fraction(&self, rp: &[f32; 4], yaw: f32, rp_span: f32) -> f32 {
        let mut k = 1.0f32;
        for i in 0..4 {
            for j in 0..4 {
                let dy = (self.coef[i][2] - self.coef[j][2]) * yaw;
                if dy > 0.0 {
                    k = k.min(((1.0 - (rp[i] - rp[j])) / dy).max(0.0));
                }
            }
        }
        if rp_span >= 1.0 {
            0.0
        } else {
            k
        }
    }
}

fn round_unit(v: f32) -> f32 {
    if v > 0.5 {
        1.0
    } else if v < -0.5 {
        -1.0
    } else {
        0.0
    }
}

fn close(a: Demand, b: Demand) -> bool {
    let tol = 1e-5;
    fabsf(a.collective - b.collective) < tol
        && fabsf(a.roll - b.roll) < tol
        && fabsf(a.pitch - b.pitch) < tol
        && fabsf(a.yaw - b.yaw) < tol
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(collective: f32, roll: f32, pitch: f32, yaw: f32) -> Demand {
        Demand {
            collective,
            roll,
            pitch,
            yaw,
        }
    }

    fn assert_close(a: f32, b: f32) {
        assert!(fabsf(a - b) < 1e-5, "{a} vs {b}");
    }

    #[test]
    fn x_frame_matches_seed_eq_20_signs() {
        // Seed eq. 20 in FRD, motor 1 (front-right): T - phi + theta_frd (+ psi_frd, but eq. 19
        // says -psi_frd). FLU: theta = -theta_frd, psi = -psi_frd, so 1 = T - roll - pitch + yaw.
        let m = Mixer::new(FrameKind::X);
        let mixed = m.mix(d(0.5, 0.1, 0.0, 0.0));
        // Roll +0.1 (left side up): left motors 3, 4 gain, right motors 1, 2 lose.
        assert_close(mixed.thrust_norm[0], 0.4);
        assert_close(mixed.thrust_norm[1], 0.4);
        assert_close(mixed.thrust_norm[2], 0.6);
        assert_close(mixed.thrust_norm[3], 0.6);
        let mixed = m.mix(d(0.5, 0.0, 0.1, 0.0));
        // Pitch +0.1 (nose down): front motors 1, 4 lose.
        assert_close(mixed.thrust_norm[0], 0.4);
        assert_close(mixed.thrust_norm[3], 0.4);
        let mixed = m.mix(d(0.5, 0.0, 0.0, 0.1));
        // Yaw +0.1 (counter-clockwise): clockwise rotors 1, 3 speed up.
        assert_close(mixed.thrust_norm[0], 0.6);
        assert_close(mixed.thrust_norm[1], 0.4);
        assert_close(mixed.motors.throttle_norm[0], sqrtf(0.6));
    }

    #[test]
    fn round_trip_recovers_the_request_when_not_saturated() {
        for frame in [FrameKind::X, FrameKind::Plus] {
            let m = Mixer::new(frame);
            for req in [
                d(0.5, 0.1, -0.05, 0.02),
                d(0.3, -0.1, 0.1, -0.1),
                d(0.6, 0.0, 0.0, 0.0),
            ] {
                let mixed = m.mix(req);
                assert!(!mixed.saturated, "{frame:?} {req:?}");
                let back = m.demand_of(&mixed.thrust_norm);
                assert_close(back.collective, req.collective);
                assert_close(back.roll, req.roll);
                assert_close(back.pitch, req.pitch);
                assert_close(back.yaw, req.yaw);
            }
        }
    }

    #[test]
    fn attitude_is_kept_whole_when_collective_saturates() {
        let m = Mixer::new(FrameKind::X);
        // Near full collective: the motors that must speed up would exceed 1.
        let mixed = m.mix(d(0.95, 0.15, 0.1, 0.0));
        assert!(mixed.saturated);
        assert_close(mixed.achieved.roll, 0.15);
        assert_close(mixed.achieved.pitch, 0.1);
        assert!(mixed.achieved.collective < 0.95);
        // And at idle collective the motors that must slow down cannot go negative: raise it.
        let mixed = m.mix(d(0.02, -0.1, 0.0, 0.0));
        assert_close(mixed.achieved.roll, -0.1);
        assert_close(mixed.achieved.collective, 0.1);
        assert!(mixed.thrust_norm.iter().all(|&f| (0.0..=1.0).contains(&f)));
    }

    #[test]
    fn yaw_gives_way_before_roll_and_pitch() {
        let m = Mixer::new(FrameKind::X);
        let mixed = m.mix(d(0.5, 0.3, 0.0, 0.4));
        assert!(mixed.saturated);
        assert_close(mixed.achieved.roll, 0.3);
        assert!(mixed.achieved.yaw > 0.0 && mixed.achieved.yaw < 0.4);
        // Spread is exactly the motors' range: yaw was reduced only as far as needed.
        let hi = mixed.thrust_norm.iter().fold(0.0f32, |a, &b| a.max(b));
        let lo = mixed.thrust_norm.iter().fold(1.0f32, |a, &b| a.min(b));
        assert_close(hi - lo, 1.0);
    }

    #[test]
    fn oversized_roll_pitch_keeps_its_direction() {
        let m = Mixer::new(FrameKind::Plus);
        let mixed = m.mix(d(0.5, 2.0, 1.0, 0.3));
        assert_close(mixed.achieved.roll / mixed.achieved.pitch, 2.0);
        assert_close(mixed.achieved.yaw, 0.0);
        assert!(mixed.thrust_norm.iter().all(|&f| (0.0..=1.0).contains(&f)));
    }

    #[test]
    fn non_finite_demand_gives_finite_commands() {
        let m = Mixer::new(FrameKind::X);
        let mixed = m.mix(d(f32::NAN, f32::INFINITY, 0.1, f32::NEG_INFINITY));
        assert!(mixed.motors.throttle_norm.iter().all(|x| x.is_finite()));
        assert!(mixed.saturated);
    }

    /// A differential that spans the motors' whole range once yaw has given way: rounding put
    /// the lower collective bound above the upper one and the mixer panicked.
    #[test]
    fn a_full_span_differential_rounded_past_the_range_still_mixes() {
        let m = Mixer::new(FrameKind::X);
        let mixed = m.mix(d(-0.9015677, 0.64702225, 0.4211114, -0.4325813));
        assert!(mixed.saturated);
        assert!(mixed.thrust_norm.iter().all(|&f| (0.0..=1.0).contains(&f)));
    }

    proptest::proptest! {
        /// Any finite demand, however far out of range, mixes to thrusts in [0, 1]: the mixer
        /// runs every control step and must never panic.
        #[test]
        fn any_finite_demand_mixes_into_the_motors_range(
            plus in proptest::bool::ANY,
            collective in -3.0f32..3.0,
            roll in -3.0f32..3.0,
            pitch in -3.0f32..3.0,
            yaw in -3.0f32..3.0,
        ) {
            let m = Mixer::new(if plus { FrameKind::Plus } else { FrameKind::X });
            let mixed = m.mix(d(collective, roll, pitch, yaw));
            proptest::prop_assert!(mixed.thrust_norm.iter().all(|&f| (0.0..=1.0).contains(&f)));
            proptest::prop_assert!(mixed.motors.throttle_norm.iter().all(|&f| (0.0..=1.0).contains(&f)));
        }
    }
}
