//! How Plumbline's flight modes appear in HEARTBEAT and are selected with MAV_CMD_DO_SET_MODE.
//!
//! MAVLink leaves the meaning of `custom_mode` to the autopilot. Plumbline's numbers:
//!
//! | custom_mode | mode      | selectable with DO_SET_MODE            |
//! |-------------|-----------|----------------------------------------|
//! | 0           | Disarmed  | no (use COMPONENT_ARM_DISARM)          |
//! | 1           | Takeoff   | no (use NAV_TAKEOFF)                   |
//! | 2           | Hold      | yes                                    |
//! | 3           | Explore   | yes                                    |
//! | 4           | Return    | yes (same as NAV_RETURN_TO_LAUNCH)     |
//! | 5           | Land      | yes (same as NAV_LAND)                 |
//! | 6           | Manual    | yes                                    |
//! | 7           | Killed    | no (use DO_FLIGHTTERMINATION)          |
//!
//! `base_mode` always carries CUSTOM_MODE_ENABLED (so a ground station reads `custom_mode`),
//! SAFETY_ARMED whenever the motors may turn, MANUAL_INPUT_ENABLED in Manual and
//! GUIDED_ENABLED in the modes that fly their own setpoints.

use mavlink::dialects::common::{MavModeFlag, MavState};
use plumbline_core::msgs::{FailsafeReason, FlightMode, GroundCommand, GroundMode};

/// The `custom_mode` number of a flight mode (table above).
pub fn custom_mode(mode: FlightMode) -> u32 {
    match mode {
        FlightMode::Disarmed => 0,
        FlightMode::Takeoff => 1,
        FlightMode::Hold => 2,
        FlightMode::Explore => 3,
        FlightMode::Return => 4,
        FlightMode::Land => 5,
        FlightMode::Manual => 6,
        FlightMode::Killed => 7,
    }
}

/// What a ground station's DO_SET_MODE with this `custom_mode` asks for, if it may select it.
pub fn command_for_custom_mode(custom: u32) -> Option<GroundCommand> {
    match custom {
        2 => Some(GroundCommand::SetMode(GroundMode::Hold)),
        3 => Some(GroundCommand::SetMode(GroundMode::Explore)),
        4 => Some(GroundCommand::Return),
        5 => Some(GroundCommand::Land),
        6 => Some(GroundCommand::SetMode(GroundMode::Manual)),
        _ => None,
    }
}

/// True when the motors may turn in this mode.
pub fn is_armed(mode: FlightMode) -> bool {
    !matches!(mode, FlightMode::Disarmed | FlightMode::Killed)
}

/// HEARTBEAT `base_mode` for a mode.
pub fn base_mode(mode: FlightMode) -> MavModeFlag {
    let mut flags = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
    if is_armed(mode) {
        flags |=
            MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED | MavModeFlag::MAV_MODE_FLAG_STABILIZE_ENABLED;
    }
    match mode {
        FlightMode::Manual => flags |= MavModeFlag::MAV_MODE_FLAG_MANUAL_INPUT_ENABLED,
        FlightMode::Takeoff
        | FlightMode::Hold
        | FlightMode::Explore
        | FlightMode::Return
        | FlightMode::Land => flags |= MavModeFlag::MAV_MODE_FLAG_GUIDED_ENABLED,
        FlightMode::Disarmed | FlightMode::Killed => {}
    }
    flags
}

/// HEARTBEAT `system_status`: standby on the ground, active in flight, critical while a
/// failsafe is in force, flight termination once killed.
pub fn system_status(mode: FlightMode, failsafe: Option<FailsafeReason>) -> MavState {
    match (mode, failsafe) {
        (FlightMode::Killed, _) => MavState::MAV_STATE_FLIGHT_TERMINATION,
        (FlightMode::Disarmed, _) => MavState::MAV_STATE_STANDBY,
        (_, Some(_)) => MavState::MAV_STATE_CRITICAL,
        (_, None) => MavState::MAV_STATE_ACTIVE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MODES: [FlightMode; 8] = [
        FlightMode::Disarmed,
        FlightMode::Takeoff,
        FlightMode::Hold,
        FlightMode::Explore,
        FlightMode::Return,
        FlightMode::Land,
        FlightMode::Manual,
        FlightMode::Killed,
    ];

    #[test]
    fn custom_modes_are_distinct_and_selectable_ones_select_their_mode() {
        for (i, a) in MODES.iter().enumerate() {
            for b in &MODES[i + 1..] {
                assert_ne!(custom_mode(*a), custom_mode(*b));
            }
        }
        let select = |m| command_for_custom_mode(custom_mode(m));
        assert_eq!(
            select(FlightMode::Hold),
            Some(GroundCommand::SetMode(GroundMode::Hold))
        );
        assert_eq!(
            select(FlightMode::Explore),
            Some(GroundCommand::SetMode(GroundMode::Explore))
        );
        assert_eq!(
            select(FlightMode::Manual),
            Some(GroundCommand::SetMode(GroundMode::Manual))
        );
        assert_eq!(select(FlightMode::Land), Some(GroundCommand::Land));
        assert_eq!(select(FlightMode::Return), Some(GroundCommand::Return));
        for m in [
            FlightMode::Disarmed,
            FlightMode::Takeoff,
            FlightMode::Killed,
        ] {
            assert_eq!(select(m), None, "{m:?}");
        }
        assert_eq!(command_for_custom_mode(99), None);
    }

    #[test]
    fn armed_flag_and_status_follow_the_mode() {
        let armed = |m| base_mode(m).contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        assert!(!armed(FlightMode::Disarmed) && !armed(FlightMode::Killed));
        assert!(armed(FlightMode::Hold) && armed(FlightMode::Manual));
        assert!(
            base_mode(FlightMode::Manual).contains(MavModeFlag::MAV_MODE_FLAG_MANUAL_INPUT_ENABLED)
        );
        assert_eq!(
            system_status(FlightMode::Disarmed, None),
            MavState::MAV_STATE_STANDBY
        );
        assert_eq!(
            system_status(FlightMode::Hold, None),
            MavState::MAV_STATE_ACTIVE
        );
        assert_eq!(
            system_status(FlightMode::Land, Some(FailsafeReason::BatteryLow)),
            MavState::MAV_STATE_CRITICAL
        );
        assert_eq!(
            system_status(FlightMode::Killed, Some(FailsafeReason::KillSwitch)),
            MavState::MAV_STATE_FLIGHT_TERMINATION
        );
    }
}
