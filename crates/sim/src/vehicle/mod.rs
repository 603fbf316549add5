//! The vehicle: its parameters (this module: mass properties, rotor layout, motors, drag,
//! battery and power, with two documented presets and TOML loading), its rigid-body
//! [`dynamics`], the [`motors`], the [`battery`] and the electrical [`power`] it draws; its
//! [`still_hover`], the least power that holds it in place, and a flight's [`hover_excess`]
//! over it.
//!
//! Rotor numbering and spin follow seed 002 eqs. 15-19, rewritten from the seed's z-down body
//! frame into Plumbline's FLU frame (DESIGN.md §3): in the square (X) configuration rotor 1 is
//! front-right, 2 back-right, 3 back-left, 4 front-left; rotors 1 and 3 spin clockwise seen from
//! above, 2 and 4 counter-clockwise. In the plus configuration rotor 1 is front, 2 right, 3 back,
//! 4 left with the same spin pattern.

pub mod battery;
pub mod dynamics;
pub mod hover_excess;
pub mod model_error;
pub mod motors;
pub mod power;
pub mod still_hover;

use crate::math::Vec3;
use battery::BatteryParams;
use serde::{Deserialize, Serialize};

/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.80665;

/// How the four rotors sit around the centre of gravity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Frame {
    /// Square configuration (seed 002 Fig. 2(b)): rotors on the diagonals.
    X,
    /// Diamond configuration: rotors on the body axes.
    Plus,
}

/// Everything the dynamics, motor, battery and power models need. SI units in every name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleParams {
    pub name: String,
    pub frame: Frame,
    pub mass_kg: f64,
    /// Principal moments of inertia (body axes are principal axes), kg m².
    pub inertia_kgm2: [f64; 3],
    /// Centre of gravity to rotor hub, m.
    pub arm_length_m: f64,
    /// Thrust per rotor = k_T Ω², N/(rad/s)².
    pub thrust_coeff: f64,
    /// Hub yawing moment per rotor = k_M Ω², N m/(rad/s)² (seed 002 eq. 15).
    pub moment_coeff: f64,
    /// Rotor (blade plus motor bell) inertia I_r, kg m² (seed 002 eqs. 17-18).
    pub rotor_inertia_kgm2: f64,
    /// Rotor speed at full command, rad/s.
    pub max_rotor_speed_radps: f64,
    /// First stage of the seed 002 motor model: command to motor state, s.
    pub motor_tau_s: f64,
    /// Second stage: motor state to rotor speed, s.
    pub rotor_tau_s: f64,
    /// Standard deviation of the per-motor thrust-coefficient mismatch, as a fraction (seed 000
    /// sec. 5.3 names motor and propeller differences as a source of jitter).
    pub motor_mismatch: f64,
    /// Linear (rotor induced) drag on the air-relative velocity, N/(m/s).
    pub drag_linear: f64,
    /// Quadratic (fuselage) drag, N/(m/s)².
    pub drag_quadratic: f64,
    /// Rotational damping, N m/(rad/s).
    pub drag_rotational: f64,
    /// Radius of the vehicle seen from above (props included), m: contact with walls.
    pub radius_m: f64,
    /// Lidar height above the centre of gravity, m.
    pub lidar_offset_z_m: f64,
    /// Shaft power to motor input power, 0..1.
    pub motor_efficiency: f64,
    /// ESC switching and conduction losses as a fraction of the power they pass, 0..1.
    pub esc_loss_fraction: f64,
    /// ESC regulator (LDO) and microcontroller power per ESC, W.
    pub esc_quiescent_w: f64,
    /// Flight controller, radio and sensors, W.
    pub avionics_w: f64,
    pub battery: BatteryParams,
}

/// A rotor: hub position in the body frame and spin (+1 counter-clockwise seen from above).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rotor {
    pub position_m: Vec3,
    pub spin: f64,
}

/// Rejected vehicle parameters, with the field and the reason.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamError(pub String);

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "vehicle parameters: {}", self.0)
    }
}

impl std::error::Error for ParamError {}

impl VehicleParams {
    /// An AscTec Pelican-like quad, the seed 002 airframe (flown in the square configuration).
    /// Mass, arm, inertia, k_T, k_M/k_T = 0.016 m, Ω_max = 838 rad/s and the motor time constants
    /// follow the Pelican model of the ETH RotorS simulator; rotor inertia is a 10-inch blade as a
    /// thin rod (5 g); the battery is the stock 3S 6000 mAh pack. Drag values are estimates.
    pub fn pelican() -> Self {
        Self {
            name: "pelican".into(),
            frame: Frame::X,
            mass_kg: 1.0,
            inertia_kgm2: [0.01, 0.01, 0.02],
            arm_length_m: 0.21,
            thrust_coeff: 9.9865e-6,
            moment_coeff: 9.9865e-6 * 0.016,
            rotor_inertia_kgm2: 1.7e-5,
            max_rotor_speed_radps: 838.0,
            motor_tau_s: 0.0125,
            rotor_tau_s: 0.025,
            motor_mismatch: 0.0,
            drag_linear: 0.1,
            drag_quadratic: 0.04,
            drag_rotational: 0.002,
            radius_m: 0.35,
            lidar_offset_z_m: 0.1,
            motor_efficiency: 0.8,
            esc_loss_fraction: 0.04,
            esc_quiescent_w: 0.05,
            avionics_w: 1.3,
            battery: BatteryParams::three_cell(6.0, 0.03),
        }
    }

    /// A 450-class in-house quad like seed 000's (Fig. 10b): F450 frame (450 mm motor to motor),
    /// 1.2 kg with a 3S 2200 mAh pack, 10x4.5 propellers. k_T puts hover near 5,300 rpm, the
    /// usual figure for this class; k_M/k_T = 0.016 m; inertia from a point-mass model of motors,
    /// arms and battery. Power constants reproduce seed 000 Fig. 12 at hover (motors about 95 %,
    /// ESCs 4 %, flight controller 1 %).
    pub fn f450() -> Self {
        Self {
            name: "f450".into(),
            frame: Frame::X,
            mass_kg: 1.2,
            inertia_kgm2: [0.0115, 0.0115, 0.021],
            arm_length_m: 0.225,
            thrust_coeff: 1.07e-5,
            moment_coeff: 1.07e-5 * 0.016,
            rotor_inertia_kgm2: 6.0e-5,
            max_rotor_speed_radps: 1000.0,
            motor_tau_s: 0.01,
            rotor_tau_s: 0.04,
            motor_mismatch: 0.02,
            drag_linear: 0.12,
            drag_quadratic: 0.05,
            drag_rotational: 0.002,
            radius_m: 0.35,
            lidar_offset_z_m: 0.08,
            motor_efficiency: 0.8,
            esc_loss_fraction: 0.04,
            esc_quiescent_w: 0.06,
            avionics_w: 1.4,
            battery: BatteryParams::three_cell(2.2, 0.025),
        }
    }

    /// A preset by name (`pelican`, `f450`).
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "pelican" => Some(Self::pelican()),
            "f450" => Some(Self::f450()),
            _ => None,
        }
    }

    /// Reads a TOML file: `base = "pelican"|"f450"` (default `f450`) and any fields to override.
    pub fn from_toml(text: &str) -> Result<Self, ParamError> {
        let mut table: toml::Table = toml::from_str(text).map_err(|e| ParamError(e.to_string()))?;
        let base_name = match table.remove("base") {
            Some(toml::Value::String(s)) => s,
            Some(other) => return Err(ParamError(format!("base must be a string, got {other:?}"))),
            None => "f450".into(),
        };
        let base = Self::preset(&base_name)
            .ok_or_else(|| ParamError(format!("unknown base {base_name}")))?;
        let mut merged = toml::Table::try_from(&base).map_err(|e| ParamError(e.to_string()))?;
        for (k, v) in table {
            match (merged.get_mut(&k), v) {
                (Some(toml::Value::Table(dst)), toml::Value::Table(src)) => dst.extend(src),
                (_, v) => {
                    merged.insert(k, v);
                }
            }
        }
        let params: Self = merged
            .try_into()
            .map_err(|e: toml::de::Error| ParamError(e.to_string()))?;
        params.validate()?;
        Ok(params)
    }

    /// Rejects unphysical values, naming the first offending field.
    pub fn validate(&self) -> Result<(), ParamError> {
        let positive = [
            ("mass_kg", self.mass_kg),
            ("inertia_kgm2[0]", self.inertia_kgm2[0]),
            ("inertia_kgm2[1]", self.inertia_kgm2[1]),
            ("inertia_kgm2[2]", self.inertia_kgm2[2]),
            ("arm_length_m", self.arm_length_m),
            ("thrust_coeff", self.thrust_coeff),
            ("moment_coeff", self.moment_coeff),
            ("max_rotor_speed_radps", self.max_rotor_speed_radps),
            ("motor_tau_s", self.motor_tau_s),
            ("rotor_tau_s", self.rotor_tau_s),
            ("radius_m", self.radius_m),
            ("motor_efficiency", self.motor_efficiency),
            ("battery.capacity_ah", self.battery.capacity_ah),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(ParamError(format!(
                    "{name} must be positive and finite, got {v}"
                )));
            }
        }
        let non_negative = [
            ("rotor_inertia_kgm2", self.rotor_inertia_kgm2),
            ("motor_mismatch", self.motor_mismatch),
            ("drag_linear", self.drag_linear),
            ("drag_quadratic", self.drag_quadratic),
            ("drag_rotational", self.drag_rotational),
            ("esc_loss_fraction", self.esc_loss_fraction),
            ("esc_quiescent_w", self.esc_quiescent_w),
            ("avionics_w", self.avionics_w),
            ("battery.resistance_ohm", self.battery.resistance_ohm),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ParamError(format!(
                    "{name} must be non-negative and finite, got {v}"
                )));
            }
        }
        if self.motor_efficiency > 1.0 || self.esc_loss_fraction >= 1.0 {
            return Err(ParamError("efficiencies must lie in (0, 1]".into()));
        }
        let [a, b, c] = self.inertia_kgm2;
        if a + b < c || a + c < b || b + c < a {
            return Err(ParamError(
                "inertia_kgm2 violates the triangle inequality".into(),
            ));
        }
        let max_thrust = 4.0 * self.thrust_coeff * self.max_rotor_speed_radps.powi(2);
        if max_thrust <= self.mass_kg * GRAVITY {
            return Err(ParamError(format!(
                "cannot hover: max thrust {max_thrust:.2} N"
            )));
        }
        Ok(())
    }

    /// Rotor hubs and spins in the body frame (see the module comment).
    pub fn rotors(&self) -> [Rotor; 4] {
        let l = self.arm_length_m;
        let (fr, br, bl, fl) = match self.frame {
            Frame::X => {
                let d = l * core::f64::consts::FRAC_1_SQRT_2;
                ((d, -d), (-d, -d), (-d, d), (d, d))
            }
            Frame::Plus => ((l, 0.0), (0.0, -l), (-l, 0.0), (0.0, l)),
        };
        let spins = [-1.0, 1.0, -1.0, 1.0];
        let xy = [fr, br, bl, fl];
        core::array::from_fn(|i| Rotor {
            position_m: Vec3::new(xy[i].0, xy[i].1, 0.0),
            spin: spins[i],
        })
    }

    pub fn inertia(&self) -> Vec3 {
        Vec3::new(
            self.inertia_kgm2[0],
            self.inertia_kgm2[1],
            self.inertia_kgm2[2],
        )
    }

    /// Rotor speed at which four equal rotors carry the weight, rad/s.
    pub fn hover_rotor_speed(&self) -> f64 {
        (self.mass_kg * GRAVITY / (4.0 * self.thrust_coeff)).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_hover_below_max_speed() {
        for p in [VehicleParams::pelican(), VehicleParams::f450()] {
            p.validate().unwrap();
            assert!(
                p.hover_rotor_speed() < 0.7 * p.max_rotor_speed_radps,
                "{}",
                p.name
            );
        }
    }

    #[test]
    fn toml_overrides_a_base_and_rejects_bad_values() {
        let p = VehicleParams::from_toml(
            "base = \"pelican\"\nmass_kg = 1.3\nframe = \"plus\"\n[battery]\ncapacity_ah = 5.0\n",
        )
        .unwrap();
        assert_eq!(
            (p.mass_kg, p.frame, p.battery.capacity_ah),
            (1.3, Frame::Plus, 5.0)
        );
        assert_eq!(p.arm_length_m, VehicleParams::pelican().arm_length_m);
        let neg = VehicleParams::from_toml("mass_kg = -1.0").unwrap_err();
        assert!(neg.0.contains("mass_kg"), "{neg}");
        let zero = VehicleParams::from_toml("inertia_kgm2 = [0.01, 0.0, 0.02]").unwrap_err();
        assert!(zero.0.contains("inertia"), "{zero}");
        assert!(VehicleParams::from_toml("mass_kgg = 1.0").is_err());
        assert!(VehicleParams::from_toml("mass_kg = 20.0")
            .unwrap_err()
            .0
            .contains("hover"));
    }

    #[test]
    fn x_and_plus_layouts_sit_on_the_arm_circle_and_balance() {
        for frame in [Frame::X, Frame::Plus] {
            let p = VehicleParams {
                frame,
                ..VehicleParams::f450()
            };
            let r = p.rotors();
            let sum = r.iter().fold(Vec3::ZERO, |a, r| a + r.position_m);
            assert!(sum.norm() < 1e-12);
            assert!(r
                .iter()
                .all(|r| (r.position_m.norm() - p.arm_length_m).abs() < 1e-12));
            assert_eq!(r.iter().map(|r| r.spin).sum::<f64>(), 0.0);
        }
        let x = VehicleParams::f450().rotors();
        assert!(
            x[0].position_m.x > 0.0 && x[0].position_m.y < 0.0,
            "rotor 1 is front-right"
        );
    }
}
