#!/usr/bin/env python3
"""Independent check of troupe's dynamics against its own URDF export, with Pinocchio.

Usage: urdf_dynamics.py CASE.json

CASE.json (written by runtime/formats/tests/pinocchio_dynamics.rs) names a URDF file
(`troupe export urdf` output), whether its root is fixed, the DOF names in troupe's
order, and states {q, qd, qdd, tau} with troupe's torques. Everything about the body
comes from the URDF file alone: Pinocchio reads links and joints; troupe's armature (a
rotor inertia that core URDF cannot express) is read here from the file's transmissions,
where the export writes it as Drake's `drake:rotor_inertia` (gear ratio 1), and set on
Pinocchio's model. For each state this script runs Pinocchio's RNEA, and ABA with
troupe's torques.
It prints one JSON object: the largest torque difference (absolute, and relative to the
state's largest torque) and the DOF where it occurs; the same without the armature;
whether ABA returned finite accelerations with and without the armature; and how far
ABA's accelerations (with it) are from the state's qdd.
"""
import json
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin


DRAKE = "{http://drake.mit.edu}"


def urdf_armature(path):
    """Reflected inertia per joint name from the URDF's transmissions (Drake's convention:
    rotor inertia times the gear ratio squared)."""
    armature = {}
    for t in ET.parse(path).getroot().iter("transmission"):
        joint = t.find("joint").get("name")
        actuator = t.find("actuator")
        rotor = float(actuator.find(DRAKE + "rotor_inertia").get("value"))
        ratio = float(actuator.find(DRAKE + "gear_ratio").get("value"))
        armature[joint] = rotor * ratio * ratio
    return armature


def main(path):
    with open(path) as f:
        case = json.load(f)
    model = pin.buildModelFromUrdf(case["urdf"])
    data = model.createData()
    # URDF is Z up (troupe's Y up is written as Z): gravity along -Z.
    model.gravity = pin.Motion(np.array([0.0, 0.0, -case["gravity"], 0.0, 0.0, 0.0]))
    names = case["dofs"]
    armature = urdf_armature(case["urdf"])
    fixed = case["fixed_root"]
    # Which troupe DOFs the URDF has (a fixed root drops the root's six) and where
    # Pinocchio keeps them.
    used = [i for i, n in enumerate(names) if model.existJointName(n)]
    joints = [model.joints[model.getJointId(names[i])] for i in used]
    index = [j.idx_v for j in joints]
    if model.nv != len(used):
        raise SystemExit(f"{model.nv} Pinocchio velocities for {len(used)} troupe DOFs")
    for i, n in enumerate(names):
        if i not in used and not fixed:
            raise SystemExit(f"DOF {n} is missing from the URDF")
    # troupe's armature (from the file's transmissions) goes on
    # Pinocchio's model, whose RNEA adds armature * qdd and whose ABA adds it to the
    # articulated inertia.
    arm = np.zeros(model.nv)
    for i, k in zip(used, index):
        arm[k] = armature.get(names[i], 0.0)
    model.armature = arm
    worst = {"relative": 0.0, "absolute": 0.0, "dof": None}
    aba_worst = 0.0
    bare_worst, bare_dof = 0.0, None
    aba_finite = True
    for state in case["states"]:
        q = np.zeros(model.nq)
        qd, qdd, tau = (np.zeros(model.nv) for _ in range(3))
        for i, j, k in zip(used, joints, index):
            qd[k], qdd[k], tau[k] = (state[x][i] for x in ("qd", "qdd", "tau"))
            if j.nq == 2:
                # A continuous joint keeps (cos, sin) of its angle.
                q[j.idx_q], q[j.idx_q + 1] = np.cos(state["q"][i]), np.sin(state["q"][i])
            else:
                q[j.idx_q] = state["q"][i]
        pin_tau = pin.rnea(model, data, q, qd, qdd)
        scale = np.max(np.abs(pin_tau))
        # What a tool that ignores troupe's armature sees (the 2.4 %).
        bare = pin_tau - arm * qdd
        k = int(np.argmax(np.abs(bare - tau)))
        if abs(bare[k] - tau[k]) / scale > bare_worst:
            bare_worst = float(abs(bare[k] - tau[k]) / scale)
            bare_dof = names[used[index.index(k)]]
        diff = np.abs(pin_tau - tau)
        k = int(np.argmax(diff))
        if diff[k] / scale > worst["relative"]:
            name = names[used[index.index(k)]]
            worst = {"relative": float(diff[k] / scale), "absolute": float(diff[k]), "dof": name,
                     "troupe": float(tau[k]), "pinocchio": float(pin_tau[k]), "scale": float(scale)}
        # A tool that knows nothing of troupe's armature still gets finite accelerations:
        # every moving link of the file has a mass and an inertia.
        model.armature = np.zeros(model.nv)
        if not np.all(np.isfinite(pin.aba(model, data, q, qd, tau))):
            aba_finite = False
        model.armature = arm
        acc = pin.aba(model, data, q, qd, tau)
        if not np.all(np.isfinite(acc)):
            aba_finite = False
        else:
            aba_worst = max(aba_worst, float(np.max(np.abs(acc - qdd)) / max(1.0, np.max(np.abs(qdd)))))
    print(json.dumps({"states": len(case["states"]), "torque": worst,
                      "without_armature_relative": bare_worst,
                      "without_armature_dof": bare_dof,
                      "aba_finite": aba_finite, "aba_relative": aba_worst,
                      "pinocchio": pin.__version__}))


if __name__ == "__main__":
    main(sys.argv[1])
