"""Writes what a pymavlink ground station sends, for the link's tests and fuzz seed.

ground-unsigned.bin: a GCS heartbeat, arm, take-off to 1.5 m, DO_SET_MODE explore (custom
mode 3), manual sticks, the three parameter requests (a set of POS_XY_P to 2.5), then land
and flight termination, all to system 1 component 1, unsigned.
ground-signed.bin: the same kill (flight termination) signed with the key of 32 bytes of 7,
link id 0, timestamp 600000000000 (10 us since 2015-01-01, i.e. Unix time 1426070400 s).
autopilot-estimate.bin: what an autopilot (system 1 component 1) streams to its companion: a
heartbeat, LOCAL_POSITION_NED (2 m north, 1 m east, 1.5 m up) and ATTITUDE (yaw 0.5 rad) at
boot time 61.5 s, ODOMETRY in LOCAL_NED (the same pose, quality 80, reset counter 2) and a failed
one (quality -1), then a LOCAL_POSITION_NED with a NaN north.

Run with pymavlink 2.4.50: python3 make_ground_streams.py
"""
import os

os.environ["MAVLINK20"] = "1"
from pymavlink.dialects.v20 import common as mavlink2  # noqa: E402


class Sink:
    def __init__(self):
        self.data = bytearray()

    def write(self, b):
        self.data += b


def ground():
    sink = Sink()
    mav = mavlink2.MAVLink(sink, srcSystem=255, srcComponent=190)
    return sink, mav


sink, mav = ground()
mav.heartbeat_send(mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0)
mav.command_long_send(1, 1, mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0)
mav.command_long_send(1, 1, mavlink2.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 0, 1.5)
mav.command_long_send(1, 1, mavlink2.MAV_CMD_DO_SET_MODE, 0, 1, 3, 0, 0, 0, 0, 0)
mav.manual_control_send(1, 200, -100, 600, 0, 0)
mav.param_request_list_send(1, 1)
mav.param_request_read_send(1, 1, b"POS_XY_P", -1)
mav.param_set_send(1, 1, b"POS_XY_P", 2.5, mavlink2.MAV_PARAM_TYPE_REAL32)
mav.command_long_send(1, 1, mavlink2.MAV_CMD_NAV_LAND, 0, 0, 0, 0, 0, 0, 0, 0)
mav.command_long_send(1, 1, mavlink2.MAV_CMD_DO_FLIGHTTERMINATION, 0, 1, 0, 0, 0, 0, 0, 0)
with open("ground-unsigned.bin", "wb") as f:
    f.write(sink.data)

sink, mav = ground()
mav.signing.secret_key = bytes([7] * 32)
mav.signing.link_id = 0
mav.signing.timestamp = 600000000000
mav.signing.sign_outgoing = True
mav.command_long_send(1, 1, mavlink2.MAV_CMD_DO_FLIGHTTERMINATION, 0, 1, 0, 0, 0, 0, 0, 0)
with open("ground-signed.bin", "wb") as f:
    f.write(sink.data)

sink = Sink()
mav = mavlink2.MAVLink(sink, srcSystem=1, srcComponent=1)
mav.heartbeat_send(mavlink2.MAV_TYPE_QUADROTOR, mavlink2.MAV_AUTOPILOT_PX4, 0, 0, 0)
mav.local_position_ned_send(61500, 2.0, 1.0, -1.5, 0.0, 0.0, 0.0)
mav.attitude_send(61500, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0)
q = [0.9689124, 0.0, 0.0, 0.247404]  # yaw 0.5 rad
unknown = [float("nan")] + [0.0] * 20
for quality in (80, -1):
    mav.odometry_send(61_510_000, mavlink2.MAV_FRAME_LOCAL_NED, mavlink2.MAV_FRAME_BODY_FRD,
                      2.0, 1.0, -1.5, q, 0, 0, 0, 0, 0, 0, unknown, unknown, 2,
                      mavlink2.MAV_ESTIMATOR_TYPE_NAIVE, quality)
mav.local_position_ned_send(61520, float("nan"), 1.0, -1.5, 0.0, 0.0, 0.0)
with open("autopilot-estimate.bin", "wb") as f:
    f.write(sink.data)
