"""End-to-end tests of rsm-dump (tools/dump) on the protocol vectors.

rsm-dump comes from the CMake build named by RSM_BUILD_DIR (ctest sets it).
The vectors are tests/data/vectors.json (docs/reference/protocols.md section 3).
"""

import json
import os
import pty
import subprocess
import tty
from pathlib import Path

import pytest

from conftest import built_tool, load_vectors


# ---- helpers -----------------------------------------------------------------


def vector(name: str) -> dict:
    for v in load_vectors():
        if v["name"] == name:
            return v
    pytest.fail(f"vector {name} missing from {VECTORS}", pytrace=False)


def vbytes(v: dict) -> bytes:
    return bytes.fromhex(v["hex"].replace(" ", ""))


def _no_nan(token):
    raise ValueError(f"non-finite number {token} in output")


def parse_lines(text: str) -> list:
    """Every stdout line must be one valid, finite JSON object."""
    objs = []
    for line in text.splitlines():
        obj = json.loads(line, parse_constant=_no_nan)
        assert isinstance(obj, dict), line
        objs.append(obj)
    return objs


def run_dump(args, data=None, timeout=60):
    res = subprocess.run([str(built_tool("tools/dump/rsm-dump")), *args], input=data, capture_output=True, timeout=timeout)
    return res


def dump_bytes(tmp_path: Path, protocol: str, data: bytes, name="in.bin"):
    f = tmp_path / name
    f.write_bytes(data)
    res = run_dump(["--protocol", protocol, str(f)])
    assert res.returncode == 0, res.stderr.decode()
    objs = parse_lines(res.stdout.decode())
    assert objs and objs[-1].get("summary") is True, objs
    return objs[:-1], objs[-1]


def hexnum(s) -> int:
    return int(s, 16) if isinstance(s, str) else int(s)


# ---- the vectors ------------------------------------------------------------------

# Vector fields that are derived from, or about, other packets (deltas against
# a previous packet, human-readable notes): not fields of this frame.
NOT_FRAME_FIELDS = {"previous_xpos_raw", "delta_x_units", "previous_left", "previous_right",
                    "delta_left", "delta_right", "meaning"}

ARIA_FIELD = {  # vector key -> rsm-dump key in "fields"
    "name": "name", "class": "class", "subclass": "subclass",
    "xpos_raw": "xpos", "ypos_raw": "ypos", "thpos_raw": "thpos", "th_deg": "th_deg",
    "lvel_mm_s": "l_vel", "rvel_mm_s": "r_vel", "battery_dV": "battery",
    "stall_bumpers": "stall_and_bumpers", "left_stall": "left_stall", "right_stall": "right_stall",
    "control": "control", "flags": "flags", "motors_enabled": "motors_enabled", "estop": "estop",
    "compass_raw": "compass", "grip_state": "grip_state", "anport": "anport", "analog": "analog",
    "digin": "digin", "digout": "digout", "batteryX10": "battery_x10", "chargestate": "charge_state",
    "rotvel_raw": "rot_vel", "rotvel_deg_s": "rot_vel_deg_s", "faultflags": "fault_flags",
    "left_count": "left", "right_count": "right",
}


def same(expected, actual) -> bool:
    if isinstance(expected, bool) or isinstance(actual, bool):
        return expected is actual
    if isinstance(expected, str) and expected.lower().startswith("0x"):
        return hexnum(expected) == hexnum(actual)
    if isinstance(expected, float) or isinstance(actual, float):
        return abs(float(expected) - float(actual)) < 1e-6
    return expected == actual


def check_aria(v: dict, frames: list):
    assert len(frames) == 1, frames
    fr = frames[0]
    assert fr["protocol"] == "aria" and fr["length"] == v["length"]
    fields = fr["fields"]
    for key, exp in v["fields"].items():
        if key in NOT_FRAME_FIELDS:
            continue
        if key in ("id", "type"):
            assert fr["id"] == hexnum(exp), (key, exp, fr["id"])
        elif key == "sonar":
            got = [{"num": s["num"], "range_mm": s["range"]} for s in fields["sonar"]]
            assert got == exp
            assert fields["sonar_count"] == len(exp)
        else:
            assert key in ARIA_FIELD, f"vector field {key} of {v['name']} is not checked"
            out = ARIA_FIELD[key]
            assert out in fields, (v["name"], key, fields)
            assert same(exp, fields[out]), (v["name"], key, exp, fields[out])


def check_lms(v: dict, events: list):
    f = v["fields"]
    if "ack" in f:
        assert events[0] == {"seq": 0, "protocol": "lms", "event": "ack"}
        events = events[1:]
    assert len(events) == 1, events
    t = events[0]
    assert t["event"] == "telegram"
    body = t.get("fields", {})
    for key, exp in f.items():
        if key in NOT_FRAME_FIELDS or key == "ack":
            continue
        if key == "address":
            assert hexnum(t["address"]) == hexnum(exp)
        elif key == "length":
            assert t["length"] == exp
        elif key == "command":
            assert t["cmd"] == hexnum(exp)
        elif key == "status":
            assert hexnum(t["status"]) == hexnum(exp)
        elif key in ("result", "angle_deg", "text", "count", "units"):
            assert body[key] == exp, (key, body)
        elif key == "resolution_centideg":
            assert body["resolution_cdeg"] == exp
        elif key == "count_word":
            assert hexnum(body["count_word"]) == hexnum(exp)
        elif key == "distances_mm":
            assert body["codes"] == ["ok"] * len(exp)
            assert [round(r * 1000) for r in body["ranges_m"]] == exp
        elif key == "raw_words":
            assert body["raw"] == [hexnum(x) for x in exp]
        elif key == "distance_13bit":
            scale = 0.01 if body["units"] == "cm" else 0.001
            for d, r, code in zip(exp, body["ranges_m"], body["codes"]):
                if d >= 0x1FF7:   # the top values of a 13-bit field are error codes
                    assert r is None and code != "ok"
                else:
                    assert code == "ok" and abs(r - d * scale) < 1e-9
        elif key == "flag_bits_13_15":
            assert body["flags"] == exp
        elif key == "first_5_raw":
            assert body["raw"][:5] == exp
        elif key == "value_180_raw":
            assert body["raw"][180] == exp
        elif key == "words_with_flag_bits":
            assert sum(1 for x in body["flags"] if x) == exp
        elif key == "first_flagged_index":
            assert next(i for i, x in enumerate(body["flags"]) if x) == exp
        elif key == "first_flagged_raw":
            assert body["raw"][f["first_flagged_index"]] == hexnum(exp)
        else:
            pytest.fail(f"vector field {key} of {v['name']} is not checked")


def test_dump_decodes_every_device_to_host_vector(tmp_path):
    checked = 0
    for v in load_vectors():
        if v["direction"] not in ("robot_to_host", "sensor_to_host"):
            continue
        proto = "aria" if v["protocol"] == "aria" else "lms"
        frames, summary = dump_bytes(tmp_path, proto, vbytes(v))
        assert summary["bytes"] == v["length"]
        assert summary["frames"] == 1
        assert summary["checksum_errors"] == 0 and summary["bytes_skipped"] == 0
        assert summary["decode_errors"] == 0
        assert summary["end"] == "eof"
        if proto == "aria":
            check_aria(v, frames)
        else:
            check_lms(v, frames)
        checked += 1
    assert checked == 14


def test_dump_reports_invalid_lms_readings_as_null_with_their_code(tmp_path):
    frames, _ = dump_bytes(tmp_path, "lms", vbytes(vector("lms_b0_short_cm")))
    body = frames[0]["fields"]
    assert body["ranges_m"] == [2.5, None, 12.0, None, 3.0]
    assert body["codes"] == ["ok", "no_echo", "ok", "dazzled", "ok"]
    assert body["units"] == "cm"
    b361, _ = dump_bytes(tmp_path, "lms", vbytes(vector("lms_b0_captured_361_mm")))
    assert b361[0]["fields"]["start_deg"] == 0 and b361[0]["fields"]["step_deg"] == 0.5


# ---- faults ------------------------------------------------------------------------


def flip(b: bytes, index: int, bit: int = 0) -> bytes:
    out = bytearray(b)
    out[index] ^= 1 << bit
    return bytes(out)


def aria_fault_stream() -> bytes:
    enc = vbytes(vector("aria_encoder_packet"))
    enc_w = vbytes(vector("aria_encoder_packet_wrapped"))
    sync2 = vbytes(vector("aria_sync2_reply_example"))
    sip = vbytes(vector("aria_sip_stopped_2sonar"))
    return b"".join([
        b"\x11\x22\x33\x44\x55",  # garbage: 5 skipped
        enc,                       # decoded
        flip(enc_w, 6, 3),         # checksum error; 13 bytes after its FA re-scanned, skipped
        sync2,                     # decoded
        b"\xFA\xFB\x01",           # bad length; FB 01 skipped
        sip[:10],                  # cut short, overrun by the next SIP: checksum error, 9 skipped
        sip,                       # decoded
        sip[:20],                  # cut short at the end of the stream: truncated, 19 skipped
        enc,                       # ... and the frame after it is still decoded
    ])


def lms_fault_stream() -> bytes:
    mode = vbytes(vector("lms_mode_response_addr81"))
    b0mm = vbytes(vector("lms_b0_short_mm"))
    ack_mode = vbytes(vector("lms_ack_then_mode_response"))
    pw_cap = vbytes(vector("lms_powerup_captured"))
    pw_qm = vbytes(vector("lms_powerup_quick_manual"))
    variant = vbytes(vector("lms_bb_variant_ok"))
    return b"".join([
        b"\x11\x22\x33\x44",       # garbage: 4 skipped
        mode,                      # decoded
        flip(b0mm, 7, 0),          # CRC error: all 16 bytes skipped
        ack_mode,                  # ACK + decoded
        b"\x02\x80\x00\x00",       # LEN 0: bad length, 4 skipped
        pw_cap[:8],                # cut short, overrun by the next telegram: CRC error, 8 skipped
        pw_qm,                     # decoded
        pw_qm[:10],                # cut short at the end of the stream: truncated, 10 skipped
        variant,                   # ... and the telegram after it is still decoded
    ])


def test_dump_counts_aria_faults_exactly_and_decodes_the_frames_after_them(tmp_path):
    data = aria_fault_stream()
    frames, s = dump_bytes(tmp_path, "aria", data)
    assert [(f["type"], f.get("fields", {}).get("left")) for f in frames] == [
        ("encoder", 123456), ("sync2", None), ("sip_stopped", None), ("encoder", 123456)]
    assert s["bytes"] == len(data) == 152
    assert s["frames"] == 4
    assert s["checksum_errors"] == 2
    assert s["bad_length"] == 1
    assert s["truncated"] == 1
    assert s["bytes_skipped"] == 5 + 13 + 2 + 9 + 19
    # Every byte accounted for once (aria.h invariant).
    published = sum(f["length"] for f in frames)
    assert published + s["bytes_skipped"] + s["bad_length"] + s["checksum_errors"] + s["truncated"] == len(data)


def test_dump_counts_lms_faults_exactly_and_decodes_the_telegrams_after_them(tmp_path):
    data = lms_fault_stream()
    events, s = dump_bytes(tmp_path, "lms", data)
    kinds = [e["event"] if e["event"] != "telegram" else e["type"] for e in events]
    assert kinds == ["mode", "ack", "mode", "power_on", "variant"]
    assert s["bytes"] == len(data) == 103
    assert s["frames"] == 4
    assert s["acks"] == 1 and s["naks"] == 0
    assert s["checksum_errors"] == 2
    assert s["bad_length"] == 1
    assert s["truncated"] == 1
    assert s["bytes_skipped"] == 4 + 16 + 4 + 8 + 10
    published = sum(e["length"] + 6 for e in events if e["event"] == "telegram")
    assert published + s["acks"] + s["naks"] + s["bytes_skipped"] == len(data)


# ---- other inputs ----------------------------------------------------------------------


def strip_end(objs: list) -> list:
    """The outputs minus how the input ended (eof for a file, silence for a pty)."""
    out = [dict(o) for o in objs]
    for o in out:
        if o.get("summary"):
            o.pop("end", None)
    return out


@pytest.mark.parametrize("protocol,stream", [("aria", aria_fault_stream), ("lms", lms_fault_stream)])
def test_dump_through_a_pty_matches_the_file(tmp_path, protocol, stream):
    data = stream()
    f = tmp_path / "in.bin"
    f.write_bytes(data)
    ref = run_dump(["--protocol", protocol, str(f)])
    assert ref.returncode == 0

    master, slave = pty.openpty()
    try:
        tty.setraw(slave)  # bytes written before rsm-dump sets raw mode must pass untouched
        # The whole stream waits in the pty (it fits its buffer) before
        # rsm-dump starts: the silence that ends the run can only come after
        # it, however slowly rsm-dump starts.
        os.write(master, data)
        proc = subprocess.Popen([str(built_tool("tools/dump/rsm-dump")), "--protocol", protocol, "--baud", "38400",
                                 "--timeout-ms", "700", os.ttyname(slave)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        out, err = proc.communicate(timeout=60)
    finally:
        os.close(master)
        os.close(slave)
    assert proc.returncode == 0, err.decode()
    live = parse_lines(out.decode())
    assert live[-1]["end"] == "silence"
    assert strip_end(live) == strip_end(parse_lines(ref.stdout.decode()))


def test_dump_count_stops_after_that_many_objects_and_counts_only_what_it_decoded(tmp_path):
    """--count N: N objects, then the summary; the bytes after the N-th
    frame are not decoded, so the byte counts still add up."""
    data = aria_fault_stream()
    f = tmp_path / "in.bin"
    f.write_bytes(data)
    res = run_dump(["--protocol", "aria", "--count", "2", str(f)])
    assert res.returncode == 0, res.stderr.decode()
    objs = parse_lines(res.stdout.decode())
    frames, s = objs[:-1], objs[-1]
    assert [o["type"] for o in frames] == ["encoder", "sync2"]
    assert s["end"] == "count" and s["frames"] == 2 and s["truncated"] == 0
    enc, sync2 = vbytes(vector("aria_encoder_packet")), vbytes(vector("aria_sync2_reply_example"))
    assert s["bytes"] == 5 + 2 * len(enc) + len(sync2)  # up to the end of the SYNC2 reply
    published = sum(o["length"] for o in frames)
    assert published + s["bytes_skipped"] + s["bad_length"] + s["checksum_errors"] + s["truncated"] == s["bytes"]
    full = run_dump(["--protocol", "aria", "--count", "99", str(f)])
    assert parse_lines(full.stdout.decode())[-1]["end"] == "eof"  # fewer frames than asked for


def test_dump_reads_stdin_like_the_file(tmp_path):
    data = aria_fault_stream()
    f = tmp_path / "in.bin"
    f.write_bytes(data)
    ref = run_dump(["--protocol", "aria", str(f)])
    res = run_dump(["--protocol", "aria", "-"], data=data)
    assert res.returncode == 0
    assert res.stdout == ref.stdout


def test_dump_pretty_output_is_the_same_json(tmp_path):
    data = lms_fault_stream()
    f = tmp_path / "in.bin"
    f.write_bytes(data)
    compact = parse_lines(run_dump(["--protocol", "lms", str(f)]).stdout.decode())
    text = run_dump(["--protocol", "lms", "--pretty", str(f)]).stdout.decode()
    dec = json.JSONDecoder(parse_constant=_no_nan)
    objs, pos = [], 0
    while pos < len(text):
        while pos < len(text) and text[pos].isspace():
            pos += 1
        if pos == len(text):
            break
        obj, pos = dec.raw_decode(text, pos)
        objs.append(obj)
    assert objs == compact
    assert "\n  " in text


def test_dump_exits_1_with_a_clear_message_for_a_missing_input(tmp_path):
    missing = tmp_path / "no-such-capture.bin"
    res = run_dump(["--protocol", "aria", str(missing)])
    assert res.returncode == 1
    assert res.stdout == b""
    msg = res.stderr.decode()
    assert str(missing) in msg and "No such file or directory" in msg, msg


@pytest.mark.parametrize("args", [[], ["--protocol", "aria"], ["--protocol", "can", "x"],
                                  ["--protocol", "lms", "--baud", "fast", "x"],
                                  ["--protocol", "lms", "--bogus", "x"],
                                  ["--protocol", "lms", "a", "b"],
                                  ["--protocol", "lms", "--count", "0", "x"],
                                  ["--protocol", "lms", "--count", "many", "x"]])
def test_dump_exits_2_for_bad_arguments(args):
    res = run_dump(args)
    assert res.returncode == 2, (args, res.stderr)
    assert res.stderr


def test_dump_survives_the_pty_master_closing(tmp_path):
    master, slave = pty.openpty()
    tty.setraw(slave)
    proc = subprocess.Popen([str(built_tool("tools/dump/rsm-dump")), "--protocol", "aria", os.ttyname(slave)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    os.close(slave)
    os.write(master, vbytes(vector("aria_encoder_packet")))
    # The master closes only once rsm-dump has printed the packet, however slowly it runs.
    first = proc.stdout.readline()
    os.close(master)
    out, err = proc.communicate(timeout=30)
    out = first + out
    assert proc.returncode == 0, err.decode()
    objs = parse_lines(out.decode())
    assert objs[-1]["summary"] is True
    assert objs[-1]["end"] == "io_error" and objs[-1]["errno"] != 0
    assert objs[0]["type"] == "encoder"
