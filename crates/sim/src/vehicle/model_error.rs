//! Model error: how the vehicle the simulator flies differs from the vehicle the onboard
//! software was configured for. The onboard stack is built from the nominal
//! [`VehicleParams`]; only the simulated body sees a [`ModelError`], so an adaptive controller
//! has something to adapt to and a fixed-gain one something to reject.
//!
//! Every field's neutral value leaves the body exactly as the nominal parameters make it (each
//! is applied as a multiplication by 1.0 or an addition of 0.0, which change no bit), so a run
//! without model error reproduces earlier runs bit for bit.

use super::{ParamError, VehicleParams, GRAVITY};
use core::ops::RangeInclusive;

/// Mass (and inertia) scales accepted: half to twice the nominal airframe.
pub const MASS_SCALE_RANGE: RangeInclusive<f64> = 0.5..=2.0;
/// Thrust factors of a weak motor accepted: below one half the vehicle loses yaw authority
/// before anything else is learnt.
pub const MOTOR_FACTOR_RANGE: RangeInclusive<f64> = 0.5..=1.0;
/// Centre-of-gravity offsets accepted on each body axis, m: a battery slid along its strap.
pub const CG_OFFSET_RANGE_M: RangeInclusive<f64> = -0.05..=0.05;
/// Payload masses accepted, kg.
pub const PAYLOAD_RANGE_KG: RangeInclusive<f64> = 0.0..=1.0;
/// The heaviest vehicle (nominal times the mass scale, plus the payload) must need no more
/// than this fraction of the full thrust of its rotors to hover, weak motor included: the rest
/// is the attitude loops' margin.
const MAX_HOVER_THRUST_FRACTION: f64 = 0.7;

/// One motor that gives less thrust than its siblings (a chipped propeller, a tired motor).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeakMotor {
    /// Rotor index, 0-based (rotor 1 of the module comment in [`crate::vehicle`] is index 0).
    pub index: usize,
    /// Thrust and hub moment of that rotor at a given speed, as a fraction of nominal.
    pub factor: f64,
}

/// A payload carried from the start and released at `release_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Payload {
    /// Hung at the centre of gravity, so it adds mass, not inertia, kg.
    pub mass_kg: f64,
    pub release_s: f64,
}

/// How the simulated vehicle differs from the nominal one. [`Default`] is no difference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelError {
    /// Mass and moments of inertia scale together (the extra mass spread like the rest).
    pub mass_scale: f64,
    pub weak_motor: Option<WeakMotor>,
    /// Centre of gravity relative to the geometric centre the rotors sit around, body x and y, m.
    pub cg_offset_m: [f64; 2],
    pub payload: Option<Payload>,
}

impl Default for ModelError {
    fn default() -> Self {
        Self::NONE
    }
}

/// The body the dynamics integrate at one instant: mass properties and per-rotor factors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrueBody {
    pub mass_kg: f64,
    pub inertia_kgm2: [f64; 3],
    /// Thrust and hub moment factor of each rotor.
    pub rotor_factor: [f64; 4],
    pub cg_offset_m: [f64; 2],
}

impl ModelError {
    /// The nominal vehicle.
    pub const NONE: Self = Self {
        mass_scale: 1.0,
        weak_motor: None,
        cg_offset_m: [0.0; 2],
        payload: None,
    };

    /// Rejects values outside the documented ranges, and a vehicle that the error leaves
    /// without a hover margin; the message names the offending quantity.
    pub fn validate(&self, v: &VehicleParams) -> Result<(), ParamError> {
        let bad = |what: &str, value: f64, range: &RangeInclusive<f64>| {
            ParamError(format!(
                "model error: {what} {value} is outside [{}, {}]",
                range.start(),
                range.end()
            ))
        };
        if !MASS_SCALE_RANGE.contains(&self.mass_scale) {
            return Err(bad("mass scale", self.mass_scale, &MASS_SCALE_RANGE));
        }
        if let Some(m) = self.weak_motor {
            if m.index > 3 {
                return Err(ParamError(format!(
                    "model error: weak motor {} does not exist (motors 1 to 4)",
                    m.index + 1
                )));
            }
            if !MOTOR_FACTOR_RANGE.contains(&m.factor) {
                return Err(bad("weak motor factor", m.factor, &MOTOR_FACTOR_RANGE));
            }
        }
        for (axis, d) in ["x", "y"].iter().zip(self.cg_offset_m) {
            if !CG_OFFSET_RANGE_M.contains(&d) {
                let what = format!("centre-of-gravity offset along {axis} (m)");
                return Err(bad(&what, d, &CG_OFFSET_RANGE_M));
            }
        }
        if let Some(p) = self.payload {
            if !PAYLOAD_RANGE_KG.contains(&p.mass_kg) {
                return Err(bad("payload mass (kg)", p.mass_kg, &PAYLOAD_RANGE_KG));
            }
            if !(p.release_s.is_finite() && p.release_s >= 0.0) {
                return Err(ParamError(format!(
                    "model error: payload release time {} s must be finite and >= 0",
                    p.release_s
                )));
            }
        }
        let body = self.body(v, true);
        let weakest = body
            .rotor_factor
            .iter()
            .fold(f64::INFINITY, |a, b| a.min(*b));
        // The weak rotor's pair must still balance the others in roll, pitch and yaw, so
        // the usable thrust is four times the weakest rotor's.
        let usable = 4.0 * weakest * v.thrust_coeff * v.max_rotor_speed_radps.powi(2);
        let weight = body.mass_kg * GRAVITY;
        if weight > MAX_HOVER_THRUST_FRACTION * usable {
            return Err(ParamError(format!(
                "model error: the vehicle would weigh {weight:.2} N against {usable:.2} N of \
                 balanced thrust; hovering needs at most {:.0} % of it",
                100.0 * MAX_HOVER_THRUST_FRACTION
            )));
        }
        Ok(())
    }

    /// The body with the payload on board (`carrying`) or after its release.
    pub fn body(&self, v: &VehicleParams, carrying: bool) -> TrueBody {
        let payload_kg = match self.payload {
            Some(p) if carrying => p.mass_kg,
            _ => 0.0,
        };
        let mut rotor_factor = [1.0; 4];
        if let Some(m) = self.weak_motor {
            rotor_factor[m.index] = m.factor;
        }
        TrueBody {
            mass_kg: v.mass_kg * self.mass_scale + payload_kg,
            inertia_kgm2: v.inertia_kgm2.map(|i| i * self.mass_scale),
            rotor_factor,
            cg_offset_m: self.cg_offset_m,
        }
    }

    /// When the body changes during a run (the payload's release), s.
    pub fn change_at_s(&self) -> Option<f64> {
        self.payload.map(|p| p.release_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_neutral_error_is_the_nominal_body() {
        let v = VehicleParams::f450();
        let b = ModelError::NONE.body(&v, true);
        assert_eq!(b.mass_kg, v.mass_kg);
        assert_eq!(b.inertia_kgm2, v.inertia_kgm2);
        assert_eq!(b.rotor_factor, [1.0; 4]);
        ModelError::NONE.validate(&v).unwrap();
    }

    #[test]
    fn the_payload_counts_until_it_is_released() {
        let v = VehicleParams::f450();
        let e = ModelError {
            mass_scale: 1.3,
            payload: Some(Payload {
                mass_kg: 0.2,
                release_s: 5.0,
            }),
            ..ModelError::NONE
        };
        assert!((e.body(&v, true).mass_kg - (1.3 * 1.2 + 0.2)).abs() < 1e-12);
        assert!((e.body(&v, false).mass_kg - 1.3 * 1.2).abs() < 1e-12);
        assert_eq!(e.change_at_s(), Some(5.0));
    }

    #[test]
    fn out_of_range_values_are_refused_by_name() {
        let v = VehicleParams::f450();
        let cases = [
            (
                ModelError {
                    mass_scale: f64::NAN,
                    ..ModelError::NONE
                },
                "mass scale",
            ),
            (
                ModelError {
                    weak_motor: Some(WeakMotor {
                        index: 4,
                        factor: 0.8,
                    }),
                    ..ModelError::NONE
                },
                "motor 5",
            ),
            (
                ModelError {
                    weak_motor: Some(WeakMotor {
                        index: 0,
                        factor: 0.2,
                    }),
                    ..ModelError::NONE
                },
                "weak motor factor",
            ),
            (
                ModelError {
                    cg_offset_m: [0.0, 0.2],
                    ..ModelError::NONE
                },
                "along y",
            ),
            (
                ModelError {
                    payload: Some(Payload {
                        mass_kg: 0.5,
                        release_s: -1.0,
                    }),
                    ..ModelError::NONE
                },
                "release time",
            ),
            (
                ModelError {
                    mass_scale: 2.0,
                    weak_motor: Some(WeakMotor {
                        index: 1,
                        factor: 0.5,
                    }),
                    ..ModelError::NONE
                },
                "balanced thrust",
            ),
        ];
        for (e, name) in cases {
            let msg = e.validate(&v).unwrap_err().to_string();
            assert!(msg.contains(name), "{msg} should name {name}");
        }
    }
}
