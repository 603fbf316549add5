//! The MRAC's parameters, each named with its unit, their defaults and why, and the checks that
//! reject a configuration the controller cannot fly.

use core::fmt;

/// The second-order reference model of one channel (seed 002 eq. 8): position error to a
/// velocity target, velocity error to an acceleration, each bounded. Near the command it is the
/// linear model `a = k_v (k_p (r - x) - v)`: natural frequency `sqrt(k_p k_v)`, damping
/// `sqrt(k_v / k_p) / 2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceConfig {
    /// Position error (m) to velocity target (m/s), 1/s.
    pub position_gain_per_s: f32,
    /// Velocity error (m/s) to acceleration (m/s^2), 1/s.
    pub velocity_gain_per_s: f32,
    /// Largest speed the model asks for, m/s.
    pub max_speed_m_s: f32,
    /// Largest acceleration the model asks for, m/s^2.
    pub max_accel_m_s2: f32,
}

/// The linear feedback on the reference model's tracking error (seed 002 eq. 9, `nu_pd = K e`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PdGains {
    /// Position error (m) to acceleration (m/s^2), 1/s^2.
    pub kp_per_s2: f32,
    /// Velocity error (m/s) to acceleration (m/s^2), 1/s.
    pub kd_per_s: f32,
}

/// The adaptive element: an RBF network with bias and linear terms (seed 002 eq. 11) trained
/// by the e-modified law of eq. 12, with its weights kept inside a ball.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveConfig {
    /// False flies the baseline alone: reference model, PD and feed-forward.
    pub enabled: bool,
    /// Learning rate `Gamma_W` of the bias weight (eq. 12's `Gamma_W` is a diagonal matrix
    /// here): weight change in m/s^2 per second per unit of `e^T P B` (with `P` from `Q = I`
    /// in SI units). The bias carries constant errors (mass, a weak motor).
    pub bias_learning_rate: f32,
    /// Learning rate of the linear and Gaussian weights, same units per unit of basis output.
    pub learning_rate: f32,
    /// e-modification gain `kappa` (Narendra and Annaswamy, seed 002 ref. 16), per unit of
    /// `|e|` (m and m/s together): the pull of the weights back towards zero.
    pub e_modification: f32,
    /// Width of the Gaussian bases in normalised input units (inputs are scaled to about
    /// [-1, 1]; centres fill that cube).
    pub rbf_width: f32,
    /// Speed that normalises the velocity inputs, m/s.
    pub velocity_scale_m_s: f32,
    /// Acceleration that normalises the reference-model acceleration inputs, m/s^2.
    pub accel_scale_m_s2: f32,
    /// Bound on each channel's weight vector norm (m/s^2 per unit basis): the update is
    /// projected back onto this ball.
    pub weight_bound: f32,
}

/// When the adaptive element counts as misbehaving and is switched off (weights reset, baseline
/// flies on). A non-finite weight or output always counts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FallbackConfig {
    /// Longest time a channel's weights may sit on `weight_bound` without a break, s.
    pub max_pinned_s: f32,
    /// A hedge larger than this is "saturated", m/s^2.
    pub hedge_threshold_m_s2: f32,
    /// Longest uninterrupted saturated hedge, s.
    pub max_hedged_s: f32,
}

/// Everything the MRAC is configured with. The three channels are world x, y (horizontal, one
/// set of gains) and z (vertical).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MracConfig {
    pub reference_xy: ReferenceConfig,
    pub reference_z: ReferenceConfig,
    pub pd_xy: PdGains,
    pub pd_z: PdGains,
    /// Horizontal drag per unit mass the baseline feeds forward on the reference model's
    /// velocity, 1/s (m/s^2 per m/s): the force the rotors' induced drag takes from a vehicle
    /// flying at speed, which the inversion's model leaves out. Without it the baseline flies a
    /// steady leg behind its setpoint until the position error's PD term makes up the drag
    /// (at 1 m/s and `pd_xy.kp` 6/s^2, 1.7 cm for 0.1/s), and the adaptive element learns it
    /// only slowly, from that small error.
    pub drag_feed_forward_per_s: f32,
    /// Lead on the reference model's horizontal acceleration, s: the baseline adds this times
    /// the rate of change of the model's acceleration (its jerk), so a tilt the attitude loop
    /// reaches only after about this long is asked for that much earlier. A change of path
    /// acceleration otherwise leaves the vehicle behind by the inner loops' lag.
    pub lead_s: f32,
    /// Time constant of the low-pass on that jerk, s: a step of the path's acceleration (a
    /// square's corner) becomes a lead that decays over this time, not a one-step spike.
    pub lead_filter_s: f32,
    pub adaptive: AdaptiveConfig,
    pub fallback: FallbackConfig,
}

const LEAD_S: f32 = 0.1;
const LEAD_FILTER_S: f32 = 0.05;

impl Default for MracConfig {
    /// The baseline matches the PID cascade's default stiffness, so the two differ only by
    /// what MRAC adds (smooth reference, feed-forward, adaptation): the PID's position gain
    /// (1.5/s) and velocity gain (4/s) are the reference model's, and in error terms the PID
    /// flies `a = 4 (1.5 e_p - v)`, i.e. `kp = 6/s^2, kd = 4/s` (natural frequency 2.4 rad/s,
    /// damping 0.8). Speed and acceleration bounds are the PID's output limits.
    fn default() -> Self {
        Self {
            reference_xy: ReferenceConfig {
                position_gain_per_s: 1.5,
                velocity_gain_per_s: 4.0,
                max_speed_m_s: 1.0,
                max_accel_m_s2: 4.0,
            },
            reference_z: ReferenceConfig {
                position_gain_per_s: 1.5,
                velocity_gain_per_s: 4.0,
                max_speed_m_s: 0.8,
                max_accel_m_s2: 5.0,
            },
            pd_xy: PdGains {
                kp_per_s2: 6.0,
                kd_per_s: 4.0,
            },
            pd_z: PdGains {
                kp_per_s2: 6.0,
                kd_per_s: 4.0,
            },
            // The rotor-drag coefficient the estimator's drag reading assumes
            // (crate::estimate::drag::DragConfig).
            drag_feed_forward_per_s: 0.1,
            lead_s: LEAD_S,
            lead_filter_s: LEAD_FILTER_S,
            adaptive: AdaptiveConfig {
                enabled: true,
                // Chosen on the simulator's square track in the hall (utm30lx, seeds 1-4,
                // nominal vehicle): 10 and 5 flew every seed (RMS track error 0.23-0.33 m);
                // one rate of 20 for all weights hit a wall on two seeds of three, a bias rate
                // of 40 on one of three, of 20 on one of four; one rate of 1 for all on two of
                // three.
                // With kp = 6, kd = 4 a bias rate of 10 integrates about 1.5 x (velocity
                // error + 0.57 x position error), 1.5 times the PID's vertical integral gain.
                bias_learning_rate: 10.0,
                learning_rate: 5.0,
                // The weights settle where kappa |W| balances P B (0.08 s^2 for position
                // errors): kappa = 0.01 lets them reach about 8 m/s^2, beyond the bound, so
                // the leak only acts on weights the error no longer supports.
                e_modification: 0.01,
                rbf_width: 0.6,
                velocity_scale_m_s: 1.0,
                // The accelerations paths ask for (the track's 1 m/s^2, a hold's recovery), so
                // the linear term that carries a thrust-scale error (a share of the commanded
                // acceleration) sees inputs near 1. Scaled by the model's 4 m/s^2 bound they
                // sat near 0.25 and that weight learned 16 times slower: with mass x1.3 and a
                // motor at 80 %, the error it should cancel (-0.27 x the command) correlated
                // 0.22 with its output, 0.63 with this scale.
                accel_scale_m_s2: 1.0,
                // 0.6 g: a 30 % heavier vehicle with a motor at 80 % needs about 2.6 m/s^2.
                weight_bound: 6.0,
            },
            fallback: FallbackConfig {
                max_pinned_s: 2.0,
                // Half the tilt-limited horizontal authority (about 3.6 m/s^2).
                hedge_threshold_m_s2: 2.0,
                max_hedged_s: 3.0,
            },
        }
    }
}

/// A parameter the controller cannot fly with: which one and what it must be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MracConfigError {
    pub field: &'static str,
    pub expected: &'static str,
}

impl fmt::Display for MracConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "mrac parameter {} must be {}", self.field, self.expected)
    }
}

fn positive(field: &'static str, v: f32) -> Result<(), MracConfigError> {
    // A NaN fails the comparison.
    if v > 0.0 && v < f32::INFINITY {
        Ok(())
    } else {
        Err(MracConfigError {
            field,
            expected: "a positive finite number",
        })
    }
}

fn non_negative(field: &'static str, v: f32) -> Result<(), MracConfigError> {
    if (0.0..f32::INFINITY).contains(&v) {
        Ok(())
    } else {
        Err(MracConfigError {
            field,
            expected: "zero or a positive finite number",
        })
    }
}

const REFERENCE_XY_FIELDS: [&str; 4] = [
    "reference_xy.position_gain_per_s",
    "reference_xy.velocity_gain_per_s",
    "reference_xy.max_speed_m_s",
    "reference_xy.max_accel_m_s2",
];
const REFERENCE_Z_FIELDS: [&str; 4] = [
    "reference_z.position_gain_per_s",
    "reference_z.velocity_gain_per_s",
    "reference_z.max_speed_m_s",
    "reference_z.max_accel_m_s2",
];
const PD_XY_FIELDS: [&str; 2] = ["pd_xy.kp_per_s2", "pd_xy.kd_per_s"];
const PD_Z_FIELDS: [&str; 2] = ["pd_z.kp_per_s2", "pd_z.kd_per_s"];

impl MracConfig {
    /// Checks every parameter; the first bad one is named.
    pub fn validate(&self) -> Result<(), MracConfigError> {
        for (r, names) in [
            (&self.reference_xy, REFERENCE_XY_FIELDS),
            (&self.reference_z, REFERENCE_Z_FIELDS),
        ] {
            positive(names[0], r.position_gain_per_s)?;
            positive(names[1], r.velocity_gain_per_s)?;
            positive(names[2], r.max_speed_m_s)?;
            positive(names[3], r.max_accel_m_s2)?;
        }
        for (pd, names) in [(&self.pd_xy, PD_XY_FIELDS), (&self.pd_z, PD_Z_FIELDS)] {
            // Both positive: the error dynamics matrix A = [0 1; -kp -kd] is then Hurwitz and
            // the Lyapunov equation behind eq. 12 has its positive definite solution.
            positive(names[0], pd.kp_per_s2)?;
            positive(names[1], pd.kd_per_s)?;
        }
        non_negative("drag_feed_forward_per_s", self.drag_feed_forward_per_s)?;
        non_negative("lead_s", self.lead_s)?;
        positive("lead_filter_s", self.lead_filter_s)?;
        let a = &self.adaptive;
        non_negative("adaptive.bias_learning_rate", a.bias_learning_rate)?;
        non_negative("adaptive.learning_rate", a.learning_rate)?;
        non_negative("adaptive.e_modification", a.e_modification)?;
        positive("adaptive.rbf_width", a.rbf_width)?;
        positive("adaptive.velocity_scale_m_s", a.velocity_scale_m_s)?;
        positive("adaptive.accel_scale_m_s2", a.accel_scale_m_s2)?;
        positive("adaptive.weight_bound", a.weight_bound)?;
        let f = &self.fallback;
        positive("fallback.max_pinned_s", f.max_pinned_s)?;
        positive("fallback.hedge_threshold_m_s2", f.hedge_threshold_m_s2)?;
        positive("fallback.max_hedged_s", f.max_hedged_s)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    #[test]
    fn defaults_pass_and_each_bad_value_is_named() {
        assert_eq!(MracConfig::default().validate(), Ok(()));
        let mut c = MracConfig::default();
        c.pd_z.kd_per_s = 0.0;
        assert_eq!(c.validate().unwrap_err().field, "pd_z.kd_per_s");
        let c = MracConfig {
            drag_feed_forward_per_s: -0.1,
            ..MracConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().field, "drag_feed_forward_per_s");
        let c = MracConfig {
            lead_filter_s: 0.0,
            ..MracConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().field, "lead_filter_s");
        let mut c = MracConfig::default();
        c.adaptive.rbf_width = f32::NAN;
        assert_eq!(c.validate().unwrap_err().field, "adaptive.rbf_width");
        let mut c = MracConfig::default();
        c.adaptive.learning_rate = -1.0;
        let e = c.validate().unwrap_err();
        assert_eq!(e.field, "adaptive.learning_rate");
        assert!(std::format!("{e}").contains("zero or a positive"));
        let mut c = MracConfig::default();
        c.reference_xy.max_speed_m_s = f32::INFINITY;
        assert_eq!(
            c.validate().unwrap_err().field,
            "reference_xy.max_speed_m_s"
        );
    }
}
