"""Writes what a pymavlink ground station sends, for the link's tests and fuzz seed.

ground-unsigned.bin: a GCS heartbeat, arm, take-off to 1.5 m, DO_SET_MODE explore (custom
mode 3), manual sticks, the three parameter requests (a set of POS_XY_P to 2.5), then land
and flight termination, all to system 1 component 1, unsigned.
ground-signed.bin: the same kill (flight termination) signed with the key of 32 bytes of 7,
link id 0, timestamp 600000000000 (10 us since 2015-01-01, i.e. Unix time 1426070400 s).

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
