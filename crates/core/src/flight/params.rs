//! The parameter registry: the tuning of an [`AutopilotConfig`] as a list of named, bounded
//! numbers a ground station can list, read and set (MAVLink's parameter protocol).
//!
//! Parameters are numbered in the fixed order of the table (`param_table.rs`), so an index is
//! stable for a given build. A value is set only when it is finite, within its parameter's
//! bounds and consistent with the rest of the configuration (a critical battery voltage below
//! the low one, collective bounds around hover, take-off bounds in order, an MRAC the
//! controller can fly); otherwise it is refused with the reason and nothing changes. What a
//! change does to a flying vehicle is said at [`crate::flight::autopilot::Autopilot::set_param`].

use super::autopilot::AutopilotConfig;
pub use super::param_table::ParamInfo;
use super::param_table::PARAMS;

/// Why a parameter was not set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamError {
    /// No parameter has this index (or name).
    Unknown,
    /// NaN or infinite.
    NotFinite,
    /// Outside the parameter's bounds.
    OutOfRange { min: f32, max: f32 },
    /// Within bounds, but inconsistent with another parameter: `rule` says which and how.
    Inconsistent { rule: &'static str },
    /// This parameter changes what the controller has learned: set it while disarmed.
    NotWhileArmed,
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ParamError::Unknown => write!(f, "no such parameter"),
            ParamError::NotFinite => write!(f, "value is not a finite number"),
            ParamError::OutOfRange { min, max } => write!(f, "value outside [{min}, {max}]"),
            ParamError::Inconsistent { rule } => write!(f, "refused: {rule}"),
            ParamError::NotWhileArmed => write!(f, "can only be set while disarmed"),
        }
    }
}

/// How many parameters there are.
pub fn count() -> usize {
    PARAMS.len()
}

/// Name, unit, bounds and meaning of parameter `index`.
pub fn info(index: usize) -> Option<&'static ParamInfo> {
    PARAMS.get(index).map(|p| &p.info)
}

/// The index of the parameter called `name` (exactly; a MAVLink param_id with its padding
/// removed).
pub fn find(name: &str) -> Option<usize> {
    PARAMS.iter().position(|p| p.info.name == name)
}

/// Parameter `index` in `config`.
pub fn get(config: &AutopilotConfig, index: usize) -> Option<f32> {
    PARAMS.get(index).map(|p| (p.get)(config))
}

/// Parameter `index`'s default (that of [`AutopilotConfig::default`]).
pub fn default_value(index: usize) -> Option<f32> {
    get(&AutopilotConfig::default(), index)
}

/// `config` with parameter `index` set to `value`, or why not. `armed`: the vehicle is armed
/// (some parameters are refused then).
pub fn with(
    config: &AutopilotConfig,
    index: usize,
    value: f32,
    armed: bool,
) -> Result<AutopilotConfig, ParamError> {
    let p = PARAMS.get(index).ok_or(ParamError::Unknown)?;
    if !value.is_finite() {
        return Err(ParamError::NotFinite);
    }
    let (min, max) = (p.info.min, p.info.max);
    if !(min..=max).contains(&value) {
        return Err(ParamError::OutOfRange { min, max });
    }
    if armed && !p.info.in_flight {
        return Err(ParamError::NotWhileArmed);
    }
    let mut changed = *config;
    (p.set)(&mut changed, value);
    check(&changed)?;
    Ok(changed)
}

/// The rules between parameters that no single bound can say.
fn check(c: &AutopilotConfig) -> Result<(), ParamError> {
    let s = &c.supervisor;
    let rules = [
        (
            s.battery_critical_v < s.battery_low_v,
            "FS_BATT_CRIT_V must stay below FS_BATT_LOW_V",
        ),
        (
            c.cascade.min_collective < c.cascade.hover_collective
                && c.cascade.hover_collective < c.cascade.max_collective,
            "CTL_COLL_MIN and CTL_COLL_MAX must stay either side of the hover collective",
        ),
        (
            s.link.min_takeoff_height_m <= s.link.max_takeoff_height_m,
            "TKOFF_MIN_M must not exceed TKOFF_MAX_M",
        ),
        (
            c.mrac.validate().is_ok(),
            "the MRAC configuration must stay valid",
        ),
    ];
    match rules.iter().find(|(ok, _)| !ok) {
        Some(&(_, rule)) => Err(ParamError::Inconsistent { rule }),
        None => Ok(()),
    }
}

#[cfg(test)]
#[path = "params_tests.rs"]
mod tests;
