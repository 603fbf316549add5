#!/usr/bin/env python3
"""pymavlink as the ground station of a simulated Plumbline flight.

    ground_station.py PLUMBLINE telemetry   every message the vehicle sends: fields and rates
    ground_station.py PLUMBLINE commands    parameters, a signed kill, unsigned commands refused,
                                            garbage and a PARAM_SET flood survived
    ground_station.py PLUMBLINE endurance   a 10-minute flight at 50 Hz loses no message

Each case starts `PLUMBLINE sim ... --mavlink udpout:127.0.0.1:PORT` on a port this script
has bound (so no port is guessed), plays the ground station and checks the flight's JSON
summary against what it saw. Exit status 0 when every check holds; the first failed check is
printed with what was seen.
"""
import json
import os
import random
import socket
import subprocess
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mav  # noqa: E402

VEHICLE = 1
AUTOPILOT = 1
# Default telemetry rates, Hz (plumbline-link's TelemetryRates).
RATES = {
    "HEARTBEAT": 1,
    "SYS_STATUS": 1,
    "BATTERY_STATUS": 1,
    "ATTITUDE": 50,
    "LOCAL_POSITION_NED": 50,
    "ODOMETRY": 10,
    "DISTANCE_SENSOR": 10,
    "OBSTACLE_DISTANCE": 10,
}
CUSTOM_MODE = {"disarmed": 0, "takeoff": 1, "hold": 2, "land": 5, "killed": 7}


def check(cond, what):
    if not cond:
        print(f"FAIL: {what}", flush=True)
        sys.exit(1)


def start_sim(binary, port, duration_s, extra):
    cmd = [binary, "sim", "--world", "room", "--scenario", "hold", "--lidar", "xv11",
           "--seed", "2", "--duration", str(duration_s),
           "--mavlink", f"udpout:127.0.0.1:{port}", "--json"] + extra
    print("running:", " ".join(cmd), flush=True)
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finish(proc, timeout_s):
    try:
        out, err = proc.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        check(False, f"the sim did not finish in {timeout_s} s; stderr: {err[-2000:]}")
    check(proc.returncode == 0, f"the sim exited with {proc.returncode}: {err[-2000:]}")
    return json.loads(out)


def raw_socket():
    """A UDP socket on a free loopback port with a receive buffer deep enough for bursts."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    for opt in (getattr(socket, "SO_RCVBUFFORCE", None), socket.SO_RCVBUF):
        if opt is None:
            continue
        try:
            sock.setsockopt(socket.SOL_SOCKET, opt, 64 << 20)
            break
        except OSError:
            continue
    sock.bind(("127.0.0.1", 0))
    return sock


def drain(sock, proc):
    """Every datagram until the sim has exited and the socket is quiet."""
    sock.settimeout(0.2)
    datagrams = []
    while True:
        try:
            datagrams.append(sock.recv(65536))
        except socket.timeout:
            if proc.poll() is not None:
                break
    return datagrams


def decode(datagrams):
    """(messages in order, sequence gaps, messages lost to gaps, bad frames)."""
    parser = mav.MAVLink(None)
    parser.robust_parsing = True
    messages, bad = [], 0
    for d in datagrams:
        for m in parser.parse_buffer(d) or []:
            if m.get_type() == "BAD_DATA":
                bad += 1
            else:
                messages.append(m)
    gaps, lost, prev = 0, 0, None
    for m in messages:
        seq = m.get_seq()
        if prev is not None and seq != (prev + 1) % 256:
            gaps += 1
            lost += (seq - prev - 1) % 256
        prev = seq
    return messages, gaps, lost, bad


def by_type(messages):
    out = {}
    for m in messages:
        out.setdefault(m.get_type(), []).append(m)
    return out


def check_counts(types, summary):
    sent = summary["mavlink"]["sent_by_type"]
    seen = {k: len(v) for k, v in types.items()}
    check(seen == sent, f"messages per type seen {seen} vs sent {sent}")


def telemetry(binary):
    sock = raw_socket()
    duration = 20.0
    proc = start_sim(binary, sock.getsockname()[1], duration, ["--realtime", "10"])
    datagrams = drain(sock, proc)
    summary = finish(proc, 60)
    messages, gaps, lost, bad = decode(datagrams)
    types = by_type(messages)
    print(f"{len(messages)} messages in {len(datagrams)} datagrams: "
          + ", ".join(f"{k} {len(v)}" for k, v in sorted(types.items())), flush=True)
    check(bad == 0 and gaps == 0, f"{bad} bad frames, {gaps} sequence gaps ({lost} lost)")
    check_counts(types, summary)
    for m in messages:
        check(m.get_srcSystem() == VEHICLE and m.get_srcComponent() == AUTOPILOT,
              f"sender {m.get_srcSystem()}/{m.get_srcComponent()}")
        check(m.get_signed() is False, "a frame signed without a key")
    sim_s = summary["sim_seconds"]
    for name, hz in RATES.items():
        n = len(types.get(name, []))
        check(abs(n / sim_s - hz) <= 0.1 * hz + 1.0 / sim_s,
              f"{name}: {n} in {sim_s} s, expected {hz} Hz")
    # The 50 Hz streams are stamped with the vehicle's clock every 20 ms (to the millisecond).
    for name in ("ATTITUDE", "LOCAL_POSITION_NED"):
        stamps = [m.time_boot_ms for m in types[name]]
        steps = {b - a for a, b in zip(stamps, stamps[1:])}
        mean = (stamps[-1] - stamps[0]) / (len(stamps) - 1)
        check(steps <= {19, 20, 21} and abs(mean - 20) < 0.1,
              f"{name} stamp steps {sorted(steps)[:5]} ms, mean {mean}")

    hb = types["HEARTBEAT"]
    check(all(h.type == mav.MAV_TYPE_QUADROTOR for h in hb), "HEARTBEAT type")
    check(hb[0].custom_mode == CUSTOM_MODE["disarmed"], f"first mode {hb[0].custom_mode}")
    last = hb[-1]
    check(last.custom_mode == CUSTOM_MODE["hold"], f"last mode {last.custom_mode}")
    check(last.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED, "armed flag in hold")
    check(last.system_status == mav.MAV_STATE_ACTIVE, f"status {last.system_status}")
    check(summary["modes"][-1]["mode"] == "hold", f"summary modes {summary['modes']}")
    texts = [t.text for t in types["STATUSTEXT"]]
    check(any("unsigned" in t for t in texts), f"no unsigned-link warning in {texts}")
    check(any("hold" in t for t in texts), f"no mode-change text in {texts}")

    # Holding over the start: level, still, at the sonar's height.
    t_hold = next(m["t_s"] for m in summary["modes"] if m["mode"] == "hold") + 2.0
    att = [a for a in types["ATTITUDE"] if a.time_boot_ms / 1e3 > t_hold]
    check(att and all(abs(a.roll) < 0.1 and abs(a.pitch) < 0.1 for a in att),
          "attitude not level in hold")
    pos = [p for p in types["LOCAL_POSITION_NED"] if p.time_boot_ms / 1e3 > t_hold]
    check(all(abs(p.x) < 0.3 and abs(p.y) < 0.3 for p in pos), "position off the start")
    check(all(abs(p.vx) < 0.3 and abs(p.vy) < 0.3 and abs(p.vz) < 0.3 for p in pos),
          "moving in hold")
    sonar = [d for d in types["DISTANCE_SENSOR"] if d.time_boot_ms / 1e3 > t_hold]
    check(sonar, "no DISTANCE_SENSOR in hold")
    for d in sonar:
        check(d.orientation == mav.MAV_SENSOR_ROTATION_PITCH_270, "sonar not facing down")
        check(d.min_distance <= d.current_distance <= d.max_distance, "sonar out of its range")
    height_cm = sum(d.current_distance for d in sonar) / len(sonar)
    depth_cm = -100 * sum(p.z for p in pos) / len(pos)
    check(abs(height_cm - depth_cm) < 10, f"sonar {height_cm} cm vs position z {depth_cm} cm")
    odo = types["ODOMETRY"][-1]
    check((odo.x, odo.y, odo.z) == (pos[-1].x, pos[-1].y, pos[-1].z)
          or abs(odo.z - pos[-1].z) < 0.05, "ODOMETRY and LOCAL_POSITION_NED disagree")

    sys_status = types["SYS_STATUS"][-1]
    volts = sys_status.voltage_battery / 1000
    check(abs(volts - summary["battery_end_v"]) < 0.3,
          f"SYS_STATUS {volts} V vs the sim's {summary['battery_end_v']} V")
    bat = types["BATTERY_STATUS"][-1]
    check(abs(bat.voltages[0] / 1000 - volts) < 0.3 or bat.voltages[0] == 65535,
          f"BATTERY_STATUS {bat.voltages[0]} mV")

    for o in types["OBSTACLE_DISTANCE"]:
        check(len(o.distances) == 72, "OBSTACLE_DISTANCE sectors")
        check(o.frame == mav.MAV_FRAME_BODY_FRD, f"OBSTACLE_DISTANCE frame {o.frame}")
        check(o.increment == 5 or abs(o.increment_f - 5.0) < 1e-6, "sector width")
        valid = [d for d in o.distances if d != 65535]
        check(len(valid) >= 60, f"only {len(valid)} sectors with data")
        check(all(o.min_distance <= d <= o.max_distance + 1 for d in valid), "sector range")
        # The room is a few metres across: every direction sees a wall within it.
        check(min(valid) > 20 and max(valid) <= o.max_distance + 1, f"distances {valid}")
    print("telemetry: ok", flush=True)


def endurance(binary):
    """600 s of flight streamed at 50 Hz, paced so the peer keeps up on a busy machine."""
    sock = raw_socket()
    proc = start_sim(binary, sock.getsockname()[1], 600.0, ["--realtime", "60"])
    datagrams = drain(sock, proc)
    summary = finish(proc, 120)
    messages, gaps, lost, bad = decode(datagrams)
    types = by_type(messages)
    link = summary["mavlink"]
    print(f"{len(messages)} messages in {len(datagrams)} datagrams over "
          f"{summary['sim_seconds']} s; sequence gaps {gaps} ({lost} lost), bad {bad}; "
          f"sent {link['sent_messages']}, dropped {link['dropped_messages']}", flush=True)
    check(summary["sim_seconds"] >= 600.0, "the flight was shorter than 10 minutes")
    check(gaps == 0 and bad == 0, f"{gaps} sequence gaps ({lost} lost), {bad} bad frames")
    check(link["dropped_messages"] == 0, f"the vehicle dropped {link['dropped_messages']}")
    check_counts(types, summary)
    n = len(types["ATTITUDE"])
    check(abs(n - 50 * 600) <= 2, f"{n} ATTITUDE in 600 s")
    print("endurance: ok", flush=True)


class Ground:
    """A signed pymavlink ground station that keeps its heartbeat going while it waits."""

    def __init__(self, key):
        self.c = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=255,
                                            source_component=190, dialect="common")
        self.port = self.c.port.getsockname()[1]
        self.c.setup_signing(key, sign_outgoing=True)
        self.last_beat = 0.0
        self.seen = []

    def pump(self, timeout_s, want=None):
        """Messages until `want(m)` holds (returns m) or the time is up (returns None)."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            if time.monotonic() - self.last_beat > 0.05 and self.c.clients:
                self.c.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0,
                                          mav.MAV_STATE_ACTIVE)
                self.last_beat = time.monotonic()
            m = self.c.recv_match(blocking=True, timeout=0.05)
            if m is None:
                continue
            self.seen.append(m)
            if want and want(m):
                return m
        return None

    def command(self, cmd, p1=0.0, signed=True):
        self.c.mav.signing.sign_outgoing = signed
        self.c.mav.command_long_send(VEHICLE, AUTOPILOT, cmd, 0, p1, 0, 0, 0, 0, 0, 0)
        self.c.mav.signing.sign_outgoing = True

    def ack(self, cmd, timeout_s=3.0):
        return self.pump(timeout_s, lambda m: m.get_type() == "COMMAND_ACK" and m.command == cmd)


def commands(binary):
    key = bytes(random.Random(7).getrandbits(8) for _ in range(32))
    g = Ground(key)
    proc = start_sim(binary, g.port, 30.0, ["--realtime", "2", "--mavlink-key", key.hex()])
    hold = g.pump(20, lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == 2)
    check(hold is not None, "no HEARTBEAT in hold")
    check(hold.get_signed(), "the vehicle's frames are not signed with the key")

    # The parameter list, all of it, in index order.
    g.c.mav.param_request_list_send(VEHICLE, AUTOPILOT)
    params = {}
    count = None
    while count is None or len(params) < count:
        m = g.pump(3, lambda m: m.get_type() == "PARAM_VALUE")
        check(m is not None, f"PARAM_VALUE stopped after {len(params)} of {count}")
        count = m.param_count
        params[m.param_index] = (m.param_id, m.param_value)
    check(count >= 8 and sorted(params) == list(range(count)), f"{count} parameters: {params}")
    names = [n for n, _ in params.values()]
    check(len(set(names)) == count, "duplicate parameter names")
    print(f"{count} parameters: {', '.join(names)}", flush=True)

    # A value in range is applied and echoed; one far out of range is refused, the old kept.
    name, value = params[0]
    new = value * 0.9 if value != 0 else 0.01
    g.c.mav.param_set_send(VEHICLE, AUTOPILOT, name.encode(), new, mav.MAV_PARAM_TYPE_REAL32)
    echo = g.pump(3, lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == name)
    check(echo is not None and abs(echo.param_value - new) < 1e-4 * max(1, abs(new)),
          f"PARAM_SET {name}={new}: echo {echo}")
    g.c.mav.param_set_send(VEHICLE, AUTOPILOT, name.encode(), 1e9, mav.MAV_PARAM_TYPE_REAL32)
    echo = g.pump(3, lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == name)
    check(echo is not None and abs(echo.param_value - new) < 1e-4 * max(1, abs(new)),
          f"an out-of-range PARAM_SET changed {name}: {echo}")
    refusal = g.pump(3, lambda m: m.get_type() == "STATUSTEXT" and name in m.text)
    check(refusal is not None, "no STATUSTEXT for the refused parameter")

    # Unsigned commands are refused: no acceptance, the vehicle keeps holding.
    g.command(mav.MAV_CMD_NAV_LAND, signed=False)
    ack = g.ack(mav.MAV_CMD_NAV_LAND, 1.0)
    check(ack is None or ack.result != mav.MAV_RESULT_ACCEPTED, "an unsigned LAND accepted")

    # Garbage, truncated and corrupted frames, then a PARAM_SET flood.
    rng = random.Random(3)
    raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    target = next(iter(g.c.clients))
    for _ in range(50):
        raw.sendto(bytes(rng.getrandbits(8) for _ in range(rng.randrange(1, 300))), target)
    frame = mav.MAVLink_command_long_message(VEHICLE, AUTOPILOT, mav.MAV_CMD_NAV_LAND, 0,
                                             0, 0, 0, 0, 0, 0, 0).pack(mav.MAVLink(None))
    raw.sendto(frame[:-5], target)
    raw.sendto(frame[:-2] + bytes([frame[-2] ^ 0xFF, frame[-1]]), target)
    for i in range(300):
        g.c.mav.param_set_send(VEHICLE, AUTOPILOT, name.encode(), new, mav.MAV_PARAM_TYPE_REAL32)
    beat = g.pump(3, lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == 2)
    check(beat is not None, "the link stopped after garbage and a flood")

    # The signed kill stops the motors.
    g.command(mav.MAV_CMD_DO_FLIGHTTERMINATION, 1.0)
    ack = g.ack(mav.MAV_CMD_DO_FLIGHTTERMINATION)
    check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, f"kill ack {ack}")
    text = g.pump(3, lambda m: m.get_type() == "STATUSTEXT" and "killed" in m.text)
    check(text is not None, "no STATUSTEXT for the killed mode")
    # With the motors off the vehicle falls: the estimate's downward speed grows like gravity's
    # until it hits the floor (which ends the flight).
    start = len(g.seen)
    g.pump(2)
    after = g.seen[start:]
    falling = [m.vz for m in after if m.get_type() == "LOCAL_POSITION_NED"]
    check(falling and max(falling) > 2.0, f"no free fall after the kill: vz {falling[:20]}")
    for m in after:
        if m.get_type() == "HEARTBEAT":
            check(m.custom_mode == 7 and m.system_status == mav.MAV_STATE_FLIGHT_TERMINATION
                  and not m.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED,
                  f"HEARTBEAT after the kill: {m}")

    summary = finish(proc, 60)
    link = summary["mavlink"]
    print("summary mavlink:", json.dumps(link), flush=True)
    check(summary["modes"][-1]["mode"] == "killed", f"final mode {summary['modes'][-1]}")
    refused = link["refused"]
    check(refused["unsigned"] >= 1, "the unsigned command was not counted")
    check(refused["bad_crc"] >= 1 and link["skipped_bytes"] > 0, "garbage not counted")
    check(refused["rate_limited"] >= 100, "the PARAM_SET flood was not limited")
    check(link["commands_accepted"] >= 1, "the kill was not counted as accepted")
    print("commands: ok", flush=True)


def main():
    binary, case = sys.argv[1], sys.argv[2]
    {"telemetry": telemetry, "commands": commands, "endurance": endurance}[case](binary)


if __name__ == "__main__":
    main()
