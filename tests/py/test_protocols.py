"""The Python protocol encoders reproduce the reference vectors byte for byte.

The vectors are ``tests/data/vectors.json`` (docs/reference/protocols.md
section 3).
"""

import random

import pytest

from conftest import TEST_DATA, load_vectors as vector_list
from rsm_tools import protocols as p


def load_vectors():
    return {v["name"]: v for v in vector_list()}


def hx(v) -> bytes:
    return bytes.fromhex(v["hex"])


def test_every_vector_checksum_verifies():
    vec = load_vectors()
    assert len(vec) >= 55
    for name, v in vec.items():
        raw = hx(v)
        assert len(raw) == v["length"], name
        if v["protocol"] == "aria":
            t, _ = p.aria_unframe(raw)
            assert t == v["fields"].get("id", int(str(v["fields"].get("type", "0")), 16)), name
        else:
            frame = raw[1:] if raw[0] == p.LMS_ACK else raw
            p.lms_unframe(frame)


def test_aria_commands_reproduce_vectors():
    vec = load_vectors()
    built = {}
    for name, v in vec.items():
        if v["protocol"] != "aria" or v["direction"] != "host_to_robot":
            continue
        f = v["fields"]
        if name.startswith("aria_vel2"):
            built[name] = p.aria_vel2(f["left_units"], f["right_units"])
        elif "string" in f:
            built[name] = p.aria_command(f["id"], string=f["string"].encode(), nul=f["trailing_nul"])
        elif "value" in f:
            built[name] = p.aria_command(f["id"], f["value"])
        else:
            built[name] = p.aria_command(f["id"])
    assert len(built) >= 28
    for name, b in built.items():
        assert b == hx(vec[name]), name


def test_aria_checksum_examples():
    assert p.aria_checksum(bytes.fromhex("043B0100")) == 0x053B
    assert p.aria_checksum(bytes.fromhex("051BE803")) == 0xED1E
    assert p.aria_checksum(bytes.fromhex("2A2B02414200")) == 0x6E6C
    assert p.aria_packet(0x07, b"\x3b") == bytes.fromhex("FAFB04073B073B")


def test_sync2_reply_vector():
    vec = load_vectors()
    f = vec["aria_sync2_reply_example"]["fields"]
    payload = b"".join(s.encode() + b"\0" for s in (f["name"], f["class"], f["subclass"]))
    assert p.aria_packet(2, payload) == hx(vec["aria_sync2_reply_example"])


def test_encoder_packets_reproduce_vectors_and_wrap():
    vec = load_vectors()
    for name in ("aria_encoder_packet", "aria_encoder_packet_wrapped"):
        f = vec[name]["fields"]
        b = p.encode_encoder(f["left_count"], f["right_count"])
        assert b == hx(vec[name]), name
        assert p.decode_encoder(b) == (f["left_count"], f["right_count"])
    f = vec["aria_encoder_packet_wrapped"]["fields"]
    assert p.tick_delta(f["left_count"], f["previous_left"]) == f["delta_left"] == 100
    assert p.tick_delta(f["right_count"], f["previous_right"]) == f["delta_right"] == -100
    # unbounded integers are reduced modulo 2**32
    assert p.encode_encoder(2**31 + 52, -(2**31) - 4) == p.encode_encoder(-(2**31) + 52, 2**31 - 4)


def _sip_from_fields(f) -> p.Sip:
    h = lambda k, d=0: int(f[k], 16) if isinstance(f.get(k), str) else f.get(k, d)  # noqa: E731
    return p.Sip(
        xpos=f["xpos_raw"], ypos=f["ypos_raw"], thpos=f["thpos_raw"], lvel=f["lvel_mm_s"],
        rvel=f["rvel_mm_s"], battery=f["battery_dV"], stall_bumpers=h("stall_bumpers"),
        control=f.get("control", 0), flags=h("flags"), compass=f.get("compass_raw", 0),
        sonar=[(s["num"], s["range_mm"]) for s in f["sonar"]], grip_state=f.get("grip_state", 0),
        anport=f.get("anport", 0), analog=f.get("analog", 0), digin=h("digin"), digout=h("digout"),
        batteryx10=f.get("batteryX10", 0), chargestate=f.get("chargestate", 0),
        rotvel=f.get("rotvel_raw", 0), faultflags=h("faultflags"), moving=f["type"] == "0x33")


def test_sip_vectors_decode_and_reencode():
    vec = load_vectors()
    for name in ("aria_sip_stopped_2sonar", "aria_sip_moving_wrapped"):
        raw = hx(vec[name])
        s = p.decode_sip(raw)
        f = vec[name]["fields"]
        assert (s.xpos, s.ypos, s.thpos, s.lvel, s.rvel) == (
            f["xpos_raw"], f["ypos_raw"], f["thpos_raw"], f["lvel_mm_s"], f["rvel_mm_s"])
        assert s.sonar == [(x["num"], x["range_mm"]) for x in f["sonar"]]
        assert p.encode_sip(s) == raw, name
    # built from the listed fields alone (the moving vector does not list all of them)
    f = vec["aria_sip_stopped_2sonar"]["fields"]
    assert p.encode_sip(_sip_from_fields(f)) == hx(vec["aria_sip_stopped_2sonar"])


def test_lms_requests_reproduce_vectors():
    vec = load_vectors()
    n = 0
    for name, v in vec.items():
        if v["protocol"] != "lms2xx" or v["direction"] != "host_to_sensor":
            continue
        raw = hx(v)
        addr, cmd, data = p.lms_unframe(raw)
        assert p.lms_telegram(cmd, data, addr) == raw, name
        n += 1
    assert n >= 14
    assert p.lms_crc(bytes.fromhex("0200010031")) == 0x1215
    assert p.lms_telegram(0x20, b"\x00SICK_LMS")[-2:] == bytes.fromhex("BEC5")


def test_lms_replies_reproduce_vectors():
    vec = load_vectors()
    v = vec["lms_ack_then_mode_response"]
    assert hx(v)[0] == p.LMS_ACK
    assert bytes([p.LMS_ACK]) + p.lms_reply(0xA0, b"\x00") == hx(v)
    assert p.lms_reply(0xA0, b"\x00", address=0x81) == hx(vec["lms_mode_response_addr81"])
    assert bytes([p.LMS_ACK]) + p.lms_reply(0x91) == hx(vec["lms_reset_reply_0x91"])
    f = vec["lms_powerup_captured"]["fields"]
    assert p.lms_reply(0x90, f["text"].encode()) == hx(vec["lms_powerup_captured"])
    f = vec["lms_powerup_quick_manual"]["fields"]
    assert p.lms_reply(0x90, f["text"].encode(), status=0x13, address=0x81) == \
        hx(vec["lms_powerup_quick_manual"])
    assert p.lms_reply(0xBB, bytes.fromhex("01B4003200")) == hx(vec["lms_bb_variant_ok"])


def test_b0_vectors():
    vec = load_vectors()
    f = vec["lms_b0_short_cm"]["fields"]
    words = [int(w, 16) for w in f["raw_words"]]
    b = p.encode_b0(words, "cm")
    assert b == hx(vec["lms_b0_short_cm"])
    scan = p.decode_b0(b)
    assert scan.units == "cm" and scan.count == 5 and scan.status == 0x10
    assert scan.ranges() == [2.5, None, 12.0, None, 3.0]
    f = vec["lms_b0_short_mm"]["fields"]
    b = p.encode_b0_ranges([d / 1000 for d in f["distances_mm"]], "mm")
    assert b == hx(vec["lms_b0_short_mm"])
    cap = hx(vec["lms_b0_captured_361_mm"])
    scan = p.decode_b0(cap)
    f = vec["lms_b0_captured_361_mm"]["fields"]
    assert scan.count == 361 and scan.units == "mm"
    assert scan.raw[:5] == f["first_5_raw"] and scan.raw[180] == f["value_180_raw"]
    assert p.encode_b0(scan.raw, "mm") == cap


def test_range_to_raw_limits():
    assert p.range_to_raw(8.182, "mm") == 8182
    assert p.range_to_raw(8.183, "mm") == p.LMS_TOO_FAR
    assert p.range_to_raw(81.82, "cm") == 8182
    assert p.range_to_raw(81.83, "cm") == p.LMS_TOO_FAR
    assert p.range_to_raw(5.0, "cm", max_range=4.0) == p.LMS_TOO_FAR
    assert p.range_to_raw(float("nan")) == p.LMS_NO_VALUE
    assert p.range_to_raw(float("inf")) == p.LMS_NO_VALUE
    assert p.range_to_raw(0.0) == p.LMS_NO_VALUE


def test_frame_counter_finds_frames_in_noise_and_split_chunks():
    rng = random.Random(3)
    frames = [p.encode_encoder(i * 1000, -i) for i in range(20)]
    stream = b"".join(bytes(rng.randrange(256) for _ in range(rng.randrange(5))) + f for f in frames)
    fc = p.FrameCounter("aria")
    for i in range(0, len(stream), 7):
        fc.feed(stream[i:i + 7])
    assert fc.types.get(0x90) == 20
    lf = [p.encode_b0_ranges([1.0 + 0.01 * i] * 181) for i in range(5)]
    lc = p.FrameCounter("lms2xx")
    s = b"\x06" + b"\x02\x99".join(lf)
    for i in range(0, len(s), 100):
        lc.feed(s[i:i + 100])
    assert lc.types.get(0xB0) == 5


def test_the_captured_scan_file_is_the_vector_of_that_name():
    """tests/data/lms_b0_captured_361_mm.txt (embedded in test_lms.c) and the
    vector in vectors.json are the same 732 bytes, and a valid 361-reading mm scan."""
    text = (TEST_DATA / "lms_b0_captured_361_mm.txt").read_text()
    data = bytes.fromhex(text.replace("*", " "))
    assert data == hx(load_vectors()["lms_b0_captured_361_mm"]) and len(data) == 732
    scan = p.decode_b0(data)
    assert scan.count == 361 and scan.units == p.UNITS_MM
