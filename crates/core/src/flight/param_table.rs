//! The table of named parameters: every tuning gain of the controllers and every hold, landing,
//! mission and failsafe setting of [`AutopilotConfig`], with its unit and bounds.
//!
//! Names follow MAVLink's param_id (at most 16 ASCII characters) and group by prefix: `PID_`
//! the cascade, `CTL_` the collective bounds, `SAS_` the manual mode's rate damping, `MRAC_`
//! the adaptive controller, `FS_` failsafes, `HOLD_`/`TKOFF_`/`LAND_` hold, take-off and
//! landing, `MIS_` the exploration mission. The bounds are those a flight can survive, wide
//! enough for any tuning worth trying and narrow enough that no single value is a crash by
//! itself (a zero position gain, a negative timeout). The vehicle's own constants (hover
//! collective, control effectiveness) are not parameters: they come from the airframe.

use super::autopilot::AutopilotConfig;

/// One named, bounded parameter and where it lives in the configuration.
#[derive(Clone, Copy, Debug)]
pub struct ParamInfo {
    /// MAVLink param_id: at most 16 ASCII characters.
    pub name: &'static str,
    pub unit: &'static str,
    pub min: f32,
    pub max: f32,
    /// False: changes the meaning of learned state; refused while the vehicle is armed.
    pub in_flight: bool,
    pub doc: &'static str,
}

pub(super) struct Param {
    pub info: ParamInfo,
    pub get: fn(&AutopilotConfig) -> f32,
    pub set: fn(&mut AutopilotConfig, f32),
}

macro_rules! param {
    ($name:literal, $unit:literal, $min:literal, $max:literal, $doc:literal, $($field:tt)+) => {
        param!(@ $name, $unit, $min, $max, true, $doc, $($field)+)
    };
    (@ $name:literal, $unit:literal, $min:literal, $max:literal, $flight:literal, $doc:literal,
     $($field:tt)+) => {
        Param {
            info: ParamInfo {
                name: $name,
                unit: $unit,
                min: $min,
                max: $max,
                in_flight: $flight,
                doc: $doc,
            },
            get: |c| c.$($field)+,
            set: |c, v| c.$($field)+ = v,
        }
    };
}

#[rustfmt::skip]
pub(super) static PARAMS: [Param; 75] = [
    param!("PID_POS_XY_P", "1/s", 0.1, 5.0, "position error to velocity, horizontal", cascade.position_xy.kp),
    param!("PID_POS_XY_MAX", "m/s", 0.1, 3.0, "largest horizontal velocity the position loop asks for", cascade.position_xy.output_limit),
    param!("PID_POS_Z_P", "1/s", 0.1, 5.0, "height error to climb rate", cascade.position_z.kp),
    param!("PID_POS_Z_MAX", "m/s", 0.1, 2.0, "largest climb rate the height loop asks for", cascade.position_z.output_limit),
    param!("PID_VEL_XY_P", "1/s", 0.5, 15.0, "velocity error to acceleration, horizontal", cascade.velocity_xy.kp),
    param!("PID_VEL_XY_I", "1/s^2", 0.0, 5.0, "integral gain of the horizontal velocity loop", cascade.velocity_xy.ki),
    param!("PID_VEL_XY_IMAX", "m/s^2", 0.0, 5.0, "bound of the horizontal velocity integral", cascade.velocity_xy.integral_limit),
    param!("PID_VEL_XY_MAX", "m/s^2", 0.5, 10.0, "largest horizontal acceleration asked for", cascade.velocity_xy.output_limit),
    param!("PID_VEL_Z_P", "1/s", 0.5, 15.0, "climb-rate error to vertical acceleration", cascade.velocity_z.kp),
    param!("PID_VEL_Z_I", "1/s^2", 0.0, 5.0, "integral gain of the climb-rate loop", cascade.velocity_z.ki),
    param!("PID_VEL_Z_IMAX", "m/s^2", 0.0, 20.0, "bound of the climb-rate integral", cascade.velocity_z.integral_limit),
    param!("PID_VEL_Z_MAX", "m/s^2", 0.5, 15.0, "largest vertical acceleration asked for", cascade.velocity_z.output_limit),
    param!("PID_ATT_RP_P", "1/s", 1.0, 30.0, "roll/pitch error to body rate", cascade.attitude_rp.kp),
    param!("PID_ATT_RP_MAX", "rad/s", 0.5, 10.0, "largest roll/pitch rate asked for", cascade.attitude_rp.output_limit),
    param!("PID_ATT_Y_P", "1/s", 0.5, 10.0, "heading error to yaw rate", cascade.attitude_yaw.kp),
    param!("PID_ATT_Y_MAX", "rad/s", 0.2, 5.0, "largest yaw rate asked for", cascade.attitude_yaw.output_limit),
    param!("PID_RATE_RP_P", "1/s", 5.0, 100.0, "roll/pitch rate error to angular acceleration", cascade.rate_rp.kp),
    param!("PID_RATE_RP_I", "1/s^2", 0.0, 100.0, "integral gain of the roll/pitch rate loop", cascade.rate_rp.ki),
    param!("PID_RATE_RP_D", "1", 0.0, 2.0, "derivative gain of the roll/pitch rate loop", cascade.rate_rp.kd),
    param!("PID_RATE_RP_IMAX", "rad/s^2", 0.0, 100.0, "bound of the roll/pitch rate integral", cascade.rate_rp.integral_limit),
    param!("PID_RATE_RP_MAX", "rad/s^2", 10.0, 500.0, "largest roll/pitch angular acceleration", cascade.rate_rp.output_limit),
    param!("PID_RATE_RP_DTAU", "s", 0.0, 0.1, "low-pass time constant of the rate derivative", cascade.rate_rp.derivative_tau_s),
    param!("PID_RATE_Y_P", "1/s", 1.0, 30.0, "yaw rate error to angular acceleration", cascade.rate_yaw.kp),
    param!("PID_RATE_Y_I", "1/s^2", 0.0, 30.0, "integral gain of the yaw rate loop", cascade.rate_yaw.ki),
    param!("PID_RATE_Y_IMAX", "rad/s^2", 0.0, 10.0, "bound of the yaw rate integral", cascade.rate_yaw.integral_limit),
    param!("PID_RATE_Y_MAX", "rad/s^2", 1.0, 50.0, "largest yaw angular acceleration", cascade.rate_yaw.output_limit),
    param!("PID_MAX_TILT", "rad", 0.05, 0.6, "largest tilt the velocity loop commands", cascade.max_tilt_rad),
    param!("PID_CMD_TAU", "s", 0.0, 1.0, "low-pass time constant of the tilt commands (0: none)", cascade.command_tau_s),
    param!("PID_OUTER_DT", "s", 0.002, 0.05, "period of the position and velocity loops", cascade.outer_period_s),
    param!("CTL_COLL_MIN", "1", 0.0, 0.3, "lowest collective (below hover)", cascade.min_collective),
    param!("CTL_COLL_MAX", "1", 0.5, 1.0, "highest collective (above hover)", cascade.max_collective),
    param!("SAS_ROLL_GAIN", "s/rad", 0.0, 0.5, "manual mode: roll deflection per rad/s of roll rate", sas.gains_per_rad_s[0]),
    param!("SAS_PITCH_GAIN", "s/rad", 0.0, 0.5, "manual mode: pitch deflection per rad/s of pitch rate", sas.gains_per_rad_s[1]),
    param!("SAS_YAW_GAIN", "s/rad", 0.0, 2.0, "manual mode: yaw deflection per rad/s of yaw rate", sas.gains_per_rad_s[2]),
    param!("SAS_ROLL_AUTH", "1", 0.0, 1.0, "manual mode: roll deflection of a full stick", sas.stick_authority[0]),
    param!("SAS_PITCH_AUTH", "1", 0.0, 1.0, "manual mode: pitch deflection of a full stick", sas.stick_authority[1]),
    param!("SAS_YAW_AUTH", "1", 0.0, 1.0, "manual mode: yaw deflection of a full stick", sas.stick_authority[2]),
    param!("MRAC_REF_XY_KP", "1/s", 0.1, 5.0, "reference model position gain, horizontal", mrac.reference_xy.position_gain_per_s),
    param!("MRAC_REF_XY_KV", "1/s", 0.5, 15.0, "reference model velocity gain, horizontal", mrac.reference_xy.velocity_gain_per_s),
    param!("MRAC_REF_XY_VMAX", "m/s", 0.1, 3.0, "reference model speed bound, horizontal", mrac.reference_xy.max_speed_m_s),
    param!("MRAC_REF_XY_AMAX", "m/s^2", 0.5, 10.0, "reference model acceleration bound, horizontal", mrac.reference_xy.max_accel_m_s2),
    param!("MRAC_REF_Z_KP", "1/s", 0.1, 5.0, "reference model position gain, vertical", mrac.reference_z.position_gain_per_s),
    param!("MRAC_REF_Z_KV", "1/s", 0.5, 15.0, "reference model velocity gain, vertical", mrac.reference_z.velocity_gain_per_s),
    param!("MRAC_REF_Z_VMAX", "m/s", 0.1, 2.0, "reference model speed bound, vertical", mrac.reference_z.max_speed_m_s),
    param!("MRAC_REF_Z_AMAX", "m/s^2", 0.5, 15.0, "reference model acceleration bound, vertical", mrac.reference_z.max_accel_m_s2),
    param!("MRAC_PD_XY_KP", "1/s^2", 0.5, 30.0, "tracking-error feedback, position, horizontal", mrac.pd_xy.kp_per_s2),
    param!("MRAC_PD_XY_KD", "1/s", 0.5, 15.0, "tracking-error feedback, velocity, horizontal", mrac.pd_xy.kd_per_s),
    param!("MRAC_PD_Z_KP", "1/s^2", 0.5, 30.0, "tracking-error feedback, position, vertical", mrac.pd_z.kp_per_s2),
    param!("MRAC_PD_Z_KD", "1/s", 0.5, 15.0, "tracking-error feedback, velocity, vertical", mrac.pd_z.kd_per_s),
    param!("MRAC_GAMMA_BIAS", "1", 0.0, 50.0, "learning rate of the bias weight", mrac.adaptive.bias_learning_rate),
    param!("MRAC_GAMMA", "1", 0.0, 50.0, "learning rate of the linear and Gaussian weights", mrac.adaptive.learning_rate),
    param!("MRAC_KAPPA", "1", 0.0, 1.0, "e-modification: pull of the weights towards zero", mrac.adaptive.e_modification),
    param!(@ "MRAC_RBF_WIDTH", "1", 0.1, 3.0, false, "width of the Gaussian bases (normalised inputs)", mrac.adaptive.rbf_width),
    param!(@ "MRAC_V_SCALE", "m/s", 0.1, 5.0, false, "speed that normalises the network's velocity inputs", mrac.adaptive.velocity_scale_m_s),
    param!(@ "MRAC_A_SCALE", "m/s^2", 0.1, 10.0, false, "acceleration that normalises its acceleration inputs", mrac.adaptive.accel_scale_m_s2),
    param!("MRAC_W_BOUND", "m/s^2", 0.1, 20.0, "bound of each channel's weight norm", mrac.adaptive.weight_bound),
    param!("MRAC_PIN_S", "s", 0.1, 30.0, "weights on their bound this long switch adaptation off", mrac.fallback.max_pinned_s),
    param!("MRAC_HEDGE_MAX", "m/s^2", 0.1, 20.0, "a hedge above this counts as saturated", mrac.fallback.hedge_threshold_m_s2),
    param!("MRAC_HEDGED_S", "s", 0.1, 30.0, "saturated hedge this long switches adaptation off", mrac.fallback.max_hedged_s),
    param!("FS_LIDAR_TMO", "s", 0.2, 5.0, "no accepted scan match this long: lidar lost, hold", supervisor.lidar_timeout_s),
    param!("FS_LIDAR_HOLD", "s", 0.0, 10.0, "lidar lost: hold this much longer, then land", supervisor.lidar_hold_s),
    param!("FS_BATT_LOW_V", "V", 3.0, 60.0, "pack voltage that lands (or returns on a mission)", supervisor.battery_low_v),
    param!("FS_BATT_CRIT_V", "V", 3.0, 60.0, "pack voltage that lands at once, faster", supervisor.battery_critical_v),
    param!("FS_BATT_DEB_S", "s", 0.0, 10.0, "a low voltage must last this long to count", supervisor.battery_debounce_s),
    param!("FS_LINK_TMO", "s", 1.0, 60.0, "ground heartbeats missing this long: link lost, hold", supervisor.link.link_timeout_s),
    param!("FS_LINK_LAND_S", "s", 0.0, 300.0, "link lost: hold this much longer, then land", supervisor.link.link_lost_land_s),
    param!("FS_STICKS_TMO", "s", 0.1, 5.0, "ground sticks missing this long end a ground manual flight", supervisor.link.sticks_timeout_s),
    param!("FS_COMP_LOST_S", "s", 0.5, 60.0, "no companion setpoint this long on a mission: land", mission.companion_lost_s),
    param!("HOLD_HEIGHT", "m", 0.3, 3.0, "take-off and hold height (taken at the next arming)", supervisor.takeoff_height_m),
    param!("TKOFF_TOL", "m", 0.01, 0.5, "take-off ends this close to the hold height", supervisor.takeoff_tolerance_m),
    param!("TKOFF_MIN_M", "m", 0.1, 10.0, "lowest take-off height a ground station may ask for", supervisor.link.min_takeoff_height_m),
    param!("TKOFF_MAX_M", "m", 0.1, 10.0, "highest take-off height a ground station may ask for", supervisor.link.max_takeoff_height_m),
    param!("LAND_SPEED", "m/s", 0.1, 2.0, "descent rate of a landing", landing.descent_m_s),
    param!("LAND_SPEED_URG", "m/s", 0.1, 3.0, "descent rate of a critical-battery or lidar-lost landing", landing.urgent_descent_m_s),
    param!("MIS_SP_TMO", "s", 0.1, 5.0, "a companion setpoint older than this is stale: hold", mission.setpoint_timeout_s),
];
