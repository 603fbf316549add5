//! Ground commands: COMMAND_LONG and MANUAL_CONTROL to core's [`GroundCommand`], and the
//! COMMAND_ACK that answers a COMMAND_LONG.

use crate::modes::command_for_custom_mode;
use mavlink::dialects::common::{
    MavCmd, MavModeFlag, MavResult, COMMAND_ACK_DATA, COMMAND_LONG_DATA, MANUAL_CONTROL_DATA,
};
use plumbline_core::msgs::{CommandResult, GroundCommand, GroundSticks};

/// MAV_RESULT for the autopilot's answer: carried out is ACCEPTED; refused in the current
/// mode or state is TEMPORARILY_REJECTED (the same command may succeed later); a bad
/// parameter is DENIED (repeating it unchanged will not help).
pub(crate) fn mav_result(result: CommandResult) -> MavResult {
    match result {
        CommandResult::Accepted => MavResult::MAV_RESULT_ACCEPTED,
        CommandResult::Refused(_) => MavResult::MAV_RESULT_TEMPORARILY_REJECTED,
        CommandResult::InvalidParameter => MavResult::MAV_RESULT_DENIED,
    }
}

/// Who sent a COMMAND_LONG and which command it was: hand it back with the autopilot's result
/// to [`crate::Link::acknowledge`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AckTo {
    pub(crate) command: MavCmd,
    pub(crate) system_id: u8,
    pub(crate) component_id: u8,
}

impl AckTo {
    /// The MAV_CMD number, for logs.
    pub fn command_number(&self) -> u16 {
        self.command as u16
    }
}

/// DO_FLIGHTTERMINATION terminates when param1 is above this (MAVLink's definition).
const TERMINATE_THRESHOLD: f32 = 0.5;

/// The core command a COMMAND_LONG asks for, or the result the link answers at once when it
/// asks for nothing the autopilot could do: UNSUPPORTED for a command Plumbline does not
/// implement, DENIED for one whose parameters select nothing (an unknown mode, arm with
/// param1 neither 0 nor 1).
pub(crate) fn ground_command(cmd: &COMMAND_LONG_DATA) -> Result<GroundCommand, MavResult> {
    match cmd.command {
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => match cmd.param1 {
            1.0 => Ok(GroundCommand::Arm),
            0.0 => Ok(GroundCommand::Disarm),
            _ => Err(MavResult::MAV_RESULT_DENIED),
        },
        MavCmd::MAV_CMD_NAV_TAKEOFF => {
            // param7 is the altitude; indoors it is the hold height above the take-off floor.
            // NaN (MAVLink's "unset") or zero keeps the configured height.
            let h = cmd.param7;
            match h {
                h if h.is_nan() || h == 0.0 => Ok(GroundCommand::Takeoff { height_m: None }),
                h if h.is_finite() && h > 0.0 => Ok(GroundCommand::Takeoff { height_m: Some(h) }),
                _ => Err(MavResult::MAV_RESULT_DENIED),
            }
        }
        MavCmd::MAV_CMD_NAV_LAND => Ok(GroundCommand::Land),
        MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH => Ok(GroundCommand::Return),
        MavCmd::MAV_CMD_DO_FLIGHTTERMINATION if cmd.param1 > TERMINATE_THRESHOLD => {
            Ok(GroundCommand::Terminate)
        }
        MavCmd::MAV_CMD_DO_FLIGHTTERMINATION => Err(MavResult::MAV_RESULT_DENIED),
        MavCmd::MAV_CMD_DO_SET_MODE => {
            let base = cmd.param1;
            let custom_flag = f32::from(MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED.bits());
            let custom = cmd.param2;
            let well_formed = base.is_finite()
                && base >= 0.0
                && (base as u32) & (custom_flag as u32) != 0
                && custom.is_finite()
                && custom >= 0.0
                && custom.fract() == 0.0;
            if !well_formed {
                return Err(MavResult::MAV_RESULT_DENIED);
            }
            command_for_custom_mode(custom as u32).ok_or(MavResult::MAV_RESULT_DENIED)
        }
        _ => Err(MavResult::MAV_RESULT_UNSUPPORTED),
    }
}

/// MANUAL_CONTROL's axes span -1000..1000; INT16_MAX marks an axis the sender does not drive.
const AXIS_FULL: f32 = 1000.0;
const AXIS_INVALID: i16 = i16::MAX;

/// Sticks from MANUAL_CONTROL: x is pitch (forward positive), y roll (right positive), r yaw
/// (clockwise positive), z thrust (0..1000). `None` when an axis is marked invalid: a takeover
/// with a missing axis is refused rather than guessed.
pub(crate) fn sticks(mc: &MANUAL_CONTROL_DATA) -> Option<GroundSticks> {
    if [mc.x, mc.y, mc.z, mc.r].contains(&AXIS_INVALID) {
        return None;
    }
    let axis = |v: i16| (f32::from(v) / AXIS_FULL).clamp(-1.0, 1.0);
    Some(GroundSticks {
        roll_norm: axis(mc.y),
        pitch_norm: axis(mc.x),
        yaw_norm: axis(mc.r),
        throttle_norm: axis(mc.z).max(0.0),
    })
}

/// The COMMAND_ACK answering `to`.
pub(crate) fn ack(to: &AckTo, result: MavResult) -> COMMAND_ACK_DATA {
    COMMAND_ACK_DATA {
        command: to.command,
        result,
        progress: 0,
        result_param2: 0,
        target_system: to.system_id,
        target_component: to.component_id,
    }
}
