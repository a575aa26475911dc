#!/usr/bin/env python3
"""VMC compatibility check with python-osc, an OSC implementation troupe does not use.

1. troupe sends an actor walking (`--vmc-out`) while recording it (`--record x.bvh`);
   python-osc parses every datagram: each must be one bundle holding /VMC/Ext/OK (int),
   /VMC/Ext/T (float), /VMC/Ext/Root/Pos and a /VMC/Ext/Bone/Pos for each of the 54 VRM
   bones troupe fills (a string and seven floats, unit quaternions); the hips' height
   (root + hips) must match troupe's own recording of the sacroiliac joint within 1 mm.
2. python-osc sends a known pose to a troupe performer: the right upper arm as in the
   T-pose (level) and the forearm turned 90° about Unity's −Y (forward, for an avatar
   facing +Z); troupe's performer must hold it: r_shoulder_abduction and
   r_elbow_flexion both 90°, no message refused.

Usage: compat.py path/to/troupe   (exits non-zero with the reason on failure)
"""
import json
import math
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time

from pythonosc import osc_bundle, osc_message, osc_bundle_builder, osc_message_builder

VRM_BONES = """Hips LeftUpperLeg LeftLowerLeg LeftFoot LeftToes RightUpperLeg RightLowerLeg
RightFoot RightToes Spine Chest UpperChest Neck Head LeftEye RightEye LeftShoulder
LeftUpperArm LeftLowerArm LeftHand RightShoulder RightUpperArm RightLowerArm RightHand
LeftThumbProximal LeftThumbIntermediate LeftThumbDistal LeftIndexProximal
LeftIndexIntermediate LeftIndexDistal LeftMiddleProximal LeftMiddleIntermediate
LeftMiddleDistal LeftRingProximal LeftRingIntermediate LeftRingDistal LeftLittleProximal
LeftLittleIntermediate LeftLittleDistal RightThumbProximal RightThumbIntermediate
RightThumbDistal RightIndexProximal RightIndexIntermediate RightIndexDistal
RightMiddleProximal RightMiddleIntermediate RightMiddleDistal RightRingProximal
RightRingIntermediate RightRingDistal RightLittleProximal RightLittleIntermediate
RightLittleDistal""".split()


def fail(msg):
    print(f"compat: FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def free_udp_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def check_frame(dgram):
    """Checks one datagram; returns (T, hips height)."""
    if not osc_bundle.OscBundle.dgram_is_bundle(dgram):
        fail("a datagram is not an OSC bundle")
    bundle = osc_bundle.OscBundle(dgram)
    seen, t, root_y, hips_y = set(), None, None, None
    for m in bundle:
        if not isinstance(m, osc_message.OscMessage):
            fail("a bundle nests another bundle")
        a, p = m.address, m.params
        if a == "/VMC/Ext/OK":
            if p != [1]:
                fail(f"/VMC/Ext/OK {p}: expected the int 1")
        elif a == "/VMC/Ext/T":
            if len(p) != 1 or not isinstance(p[0], float):
                fail(f"/VMC/Ext/T {p}: expected one float")
            t = p[0]
        elif a in ("/VMC/Ext/Root/Pos", "/VMC/Ext/Bone/Pos"):
            if len(p) != 8 or not isinstance(p[0], str) or not all(isinstance(v, float) for v in p[1:]):
                fail(f"{a} {p}: expected a string and seven floats")
            n = math.sqrt(sum(v * v for v in p[4:8]))
            if abs(n - 1) > 1e-4:
                fail(f"{a} {p[0]}: quaternion length {n}")
            if a.endswith("Root/Pos"):
                if p[0] != "root":
                    fail(f"root named {p[0]!r}")
                root_y = p[2]
            else:
                if p[0] not in VRM_BONES:
                    fail(f"bone {p[0]!r} is not a VRM humanoid bone")
                if p[0] == "Hips":
                    hips_y = p[2]
                seen.add(p[0])
        else:
            fail(f"unexpected address {a}")
    if t is None or root_y is None or hips_y is None:
        fail("a frame without T, the root or the hips")
    if seen != set(VRM_BONES):
        fail(f"bones missing: {sorted(set(VRM_BONES) - seen)}")
    # The root turns about the vertical only, so heights add.
    return t, root_y + hips_y


def receive_troupe(troupe, workdir):
    port = free_udp_port()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 8 << 20)
    sock.bind(("127.0.0.1", port))
    sock.settimeout(0.5)
    frames = []

    def listen():
        while True:
            try:
                frames.append(sock.recvfrom(65535)[0])
            except socket.timeout:
                if done.is_set():
                    return

    done = threading.Event()
    th = threading.Thread(target=listen)
    th.start()
    bvh = os.path.join(workdir, "ann.bvh")
    run = subprocess.run(
        [troupe, "run", "scripts/vmc/compat_sender.lua", "--seconds", "1.5", "--realtime",
         "--vmc-out", f"127.0.0.1:{port}=ann", "--vmc-rate", "50", "--record", bvh],
        capture_output=True, text=True)
    time.sleep(0.3)
    done.set()
    th.join()
    if run.returncode != 0:
        fail(f"troupe run failed: {run.stderr}")
    if len(frames) < 50:
        fail(f"only {len(frames)} VMC frames received")
    checked = [check_frame(f) for f in frames]
    worst = 0.0
    for t, hips in checked[::10]:
        frame = round(t * 100)
        info = subprocess.run([troupe, "seq", "info", bvh, "--positions", "--frame", str(frame), "--json"],
                              capture_output=True, text=True, check=True)
        pos = {p["joint"]: p["position"] for p in json.loads(info.stdout)["positions"]}
        worst = max(worst, abs(pos["sacroiliac"][1] / 100.0 - hips))
    if worst > 1e-3:
        fail(f"the hips' height differs from troupe's recording by {worst * 1000:.2f} mm")
    heights = [h for _, h in checked]
    print(f"compat: {len(frames)} bundles parsed by python-osc; 54 VRM bones each; hips "
          f"{min(heights):.3f}…{max(heights):.3f} m, within {worst * 1000:.3f} mm of troupe's recording")


def send_pose(troupe, workdir):
    port = free_udp_port()
    scene = os.path.join(workdir, "receiver.lua")
    with open(scene, "w") as f:
        f.write(f"""
local pat = troupe.performer{{ name = "pat", devices = {{ vmc = {{ listen = "127.0.0.1:{port}" }} }} }}
pat:capture{{}}
pat:behave(function(self)
  wait_until(function() return troupe.devices.health(self).vmc.packets > 20 end, 20)
  wait(0.2)
  print(string.format("pose r_elbow_flexion=%.4f r_shoulder_abduction=%.4f packets=%d invalid=%d",
    self:dof("r_elbow_flexion"), self:dof("r_shoulder_abduction"),
    troupe.devices.health(self).vmc.packets, troupe.devices.health(self).vmc.invalid))
end)
""")
    proc = subprocess.Popen([troupe, "--log", "warn,lua=info", "run", scene, "--realtime", "--until-idle",
                             "--max-seconds", "30"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s = math.sqrt(0.5)
    start = time.time()
    while proc.poll() is None and time.time() - start < 30:
        b = osc_bundle_builder.OscBundleBuilder(osc_bundle_builder.IMMEDIATELY)
        for addr, args in [("/VMC/Ext/OK", [1]), ("/VMC/Ext/T", [time.time() - start]),
                           ("/VMC/Ext/Root/Pos", ["root", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
                           # T-pose shoulder, forearm turned to point forward.
                           ("/VMC/Ext/Bone/Pos", ["RightUpperArm", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
                           ("/VMC/Ext/Bone/Pos", ["RightLowerArm", 0.0, 0.0, 0.0, 0.0, -s, 0.0, s])]:
            m = osc_message_builder.OscMessageBuilder(address=addr)
            for a in args:
                m.add_arg(a, "i" if isinstance(a, int) else ("s" if isinstance(a, str) else "f"))
            b.add_content(m.build())
        sock.sendto(b.build().dgram, ("127.0.0.1", port))
        time.sleep(0.02)
    out = proc.communicate(timeout=30)[0]
    line = next((l for l in out.splitlines() if "pose r_elbow_flexion=" in l), None)
    if line is None:
        fail(f"troupe's performer printed no pose:\n{out}")
    vals = dict(kv.split("=") for kv in line.split("pose ")[1].split())
    elbow, abduction = float(vals["r_elbow_flexion"]), float(vals["r_shoulder_abduction"])
    if abs(elbow - math.pi / 2) > 0.01 or abs(abduction - math.pi / 2) > 0.01 or vals["invalid"] != "0":
        fail(f"troupe holds elbow {elbow:.4f}, abduction {abduction:.4f} rad (want π/2 each): {line}")
    print(f"compat: troupe's performer holds the pose python-osc sent (elbow {math.degrees(elbow):.2f}°, "
          f"shoulder abduction {math.degrees(abduction):.2f}°)")


def main():
    troupe = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "target/debug/troupe")
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    with tempfile.TemporaryDirectory() as d:
        receive_troupe(troupe, d)
        send_pose(troupe, d)


if __name__ == "__main__":
    main()
