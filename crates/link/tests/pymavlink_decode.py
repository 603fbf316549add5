"""Decodes a file of vehicle-to-ground bytes with pymavlink, as a ground station would.

usage: pymavlink_decode.py FILE [KEY_HEX]

With KEY_HEX (64 hex digits) only frames signed with that key are accepted. Prints one JSON
object: message counts by name, frames pymavlink could not decode or whose signature it
refused, and the fields the link's test checks.
"""
import json
import os
import sys

os.environ["MAVLINK20"] = "1"
from pymavlink.dialects.v20 import common as mavlink2  # noqa: E402


def finite(value):
    """JSON has no NaN: MAVLink's "unknown" floats become null."""
    if isinstance(value, float) and value != value:
        return None
    if isinstance(value, list):
        return [finite(v) for v in value]
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    return value


def main():
    data = open(sys.argv[1], "rb").read()
    mav = mavlink2.MAVLink(None)
    mav.robust_parsing = True
    if len(sys.argv) > 2:
        mav.signing.secret_key = bytes.fromhex(sys.argv[2])
    counts, bad, fields = {}, 0, {}
    texts, acks, params, param_errors = [], [], [], []
    for msg in mav.parse_buffer(data) or []:
        name = msg.get_type()
        if name == "BAD_DATA":
            bad += 1
            continue
        counts[name] = counts.get(name, 0) + 1
        if name == "STATUSTEXT":
            texts.append(msg.text)
        elif name == "COMMAND_ACK":
            acks.append([msg.command, msg.result, msg.target_system])
        elif name == "PARAM_VALUE":
            params.append([msg.param_id, msg.param_value, msg.param_index, msg.param_count])
        elif name == "PARAM_ERROR":
            param_errors.append([msg.param_id, msg.error])
        elif name not in fields:
            fields[name] = finite(msg.to_dict())
    print(json.dumps({
        "counts": counts,
        "bad": bad,
        "rejected_signatures": mav.signing.reject_count,
        "bad_signatures": mav.signing.badsig_count,
        "good_signatures": mav.signing.goodsig_count,
        "fields": fields,
        "texts": texts,
        "acks": acks,
        "params": params,
        "param_errors": param_errors,
    }, allow_nan=False))


main()
