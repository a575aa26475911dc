#!/usr/bin/env python3
"""An independent Zenoh client (the `eclipse-zenoh` package from PyPI) that checks a
published troupe run against the .trk file the same run recorded.

It listens on a loopback endpoint, subscribes to <prefix>/actors/*/pose, starts
`troupe run SCENE --zenoh --zenoh-connect <its endpoint> --record RUN.trk --realtime`,
asks <prefix>/actors/*/dofs for the DOF names while the run goes on, decodes every
posture packet (layout in docs/formats.md, "Posture packets") and, once the run has
written its .trk, checks that each received posture equals the recorded one bit for bit.

Usage: zenoh_check.py TROUPE SCENE OUT_DIR [--ticks N]
Exit 0 when every posture matches, 1 with a message naming the first mismatch.
"""
import argparse
import bisect
import json
import socket
import struct
import subprocess
import sys
import threading
import time

import zenoh

HEADER = struct.Struct("<2sBBIQd")


def decode(payload: bytes):
    """One posture packet: (tick, time, values)."""
    magic, version, flags, n, tick, t = HEADER.unpack_from(payload)
    if magic != b"TP" or version != 1 or flags != 0:
        raise ValueError(f"not a version-1 posture packet: {payload[:4]!r}")
    if len(payload) != HEADER.size + 8 * n:
        raise ValueError(f"packet of {len(payload)} bytes for {n} DOFs")
    return tick, t, struct.unpack_from(f"<{n}d", payload, HEADER.size)


def read_trk(path):
    """{sequence: {track: ([times], [values])}} from a .trk file."""
    seqs, seq, track = {}, None, None
    with open(path) as f:
        lines = f.read().splitlines()
    if not lines or not lines[0].startswith("troupe-trk "):
        raise ValueError(f"{path}: not a .trk file")
    for line in lines[1:]:
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        if fields[0] == "sequence":
            seq = seqs.setdefault(fields[1], {})
        elif fields[0] == "track":
            track = seq.setdefault(fields[1], ([], []))
        elif fields[0] == "end":
            track = None
        elif track is not None:
            track[0].append(float(fields[0]))
            track[1].append(float(fields[1]))
    return seqs


def recorded_value(track, t):
    """The recorded value at time t: a key at t, or the key before it (the recorder
    drops only keys inside a run of equal values)."""
    times, values = track
    i = bisect.bisect_right(times, t) - 1
    if i < 0:
        raise ValueError(f"no key at or before {t}")
    return values[i]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("troupe")
    ap.add_argument("scene")
    ap.add_argument("out_dir")
    ap.add_argument("--ticks", type=int, default=300)
    args = ap.parse_args()
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    prefix = "troupe/python-check"
    trk = f"{args.out_dir}/python-check.trk"

    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("listen/endpoints", f'["{endpoint}"]')
    received, lock = [], threading.Lock()
    with zenoh.open(conf) as session:
        def on_pose(sample):
            actor = str(sample.key_expr).split("/")[-2]
            with lock:
                received.append((actor, decode(bytes(sample.payload.to_bytes()))))

        sub = session.declare_subscriber(f"{prefix}/actors/*/pose", on_pose)
        run = subprocess.Popen(
            [args.troupe, "run", args.scene, "--ticks", str(args.ticks), "--realtime",
             "--record", trk, "--zenoh", "--zenoh-connect", endpoint,
             "--zenoh-listen", "tcp/127.0.0.1:0", "--zenoh-prefix", prefix],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        dofs = {}
        deadline = time.time() + 20
        while not dofs and run.poll() is None and time.time() < deadline:
            for reply in session.get(f"{prefix}/actors/*/dofs", timeout=1.0):
                doc = json.loads(bytes(reply.ok.payload.to_bytes()))
                dofs[doc["actor"]] = doc["dofs"]
            time.sleep(0.1)
        out, _ = run.communicate(timeout=120)
        time.sleep(0.5)
        sub.undeclare()
    if run.returncode != 0:
        sys.exit(f"troupe run failed:\n{out}")
    if not dofs:
        sys.exit("no DOF names were served on <prefix>/actors/*/dofs")
    recorded = read_trk(trk)
    ticks = {}
    for actor, (tick, t, values) in received:
        names = dofs[actor]
        if len(names) != len(values):
            sys.exit(f"{actor} tick {tick}: {len(values)} values for {len(names)} DOFs")
        for name, v in zip(names, values):
            want = recorded_value(recorded[actor][name], t)
            if struct.pack("<d", v) != struct.pack("<d", want):
                sys.exit(f"{actor} tick {tick} {name}: published {v!r}, recorded {want!r}")
        ticks.setdefault(actor, []).append(tick)
    for actor in recorded:
        got = sorted(ticks.get(actor, []))
        # Interest travels after the connection: the first ticks may go before the
        # leader knows of this subscriber; after that, none may be missing.
        if not got or got[-1] != args.ticks or got != list(range(got[0], args.ticks + 1)):
            sys.exit(f"{actor}: ticks received are not a complete run to {args.ticks}: "
                     f"{len(got)} from {got[:1]}")
        if len(got) < args.ticks // 2:
            sys.exit(f"{actor}: only {len(got)} of {args.ticks + 1} ticks received")
    total = sum(len(v) for v in ticks.values())
    print(f"zenoh_check: {total} postures of {len(ticks)} actors match {trk} bit for bit")


if __name__ == "__main__":
    main()
