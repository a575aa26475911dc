-- Users' own characters: `troupe.actor{ look = FILE, bones = MAP }` (docs/lua-api.md).
local CESIUM = "../../tests/assets/characters/CesiumMan.glb"
local NO_SKIN = "../../tests/assets/characters/VRM1_humanoid_no_skin.vrm"

-- Khronos' CesiumMan names its joints its own way: a map names them by VRM bones.
local CESIUM_BONES = {
  hips = "Skeleton_torso_joint_1", spine = "Skeleton_torso_joint_2",
  upperChest = "torso_joint_3", neck = "Skeleton_neck_joint_1", head = "Skeleton_neck_joint_2",
  rightUpperArm = "Skeleton_arm_joint_R", rightLowerArm = "Skeleton_arm_joint_R__2_",
  rightHand = "Skeleton_arm_joint_R__3_", leftUpperArm = "Skeleton_arm_joint_L__4_",
  leftLowerArm = "Skeleton_arm_joint_L__3_", leftHand = "Skeleton_arm_joint_L__2_",
  rightUpperLeg = "leg_joint_R_1", rightLowerLeg = "leg_joint_R_2", rightFoot = "leg_joint_R_3",
  rightToes = "leg_joint_R_5", leftUpperLeg = "leg_joint_L_1", leftLowerLeg = "leg_joint_L_2",
  leftFoot = "leg_joint_L_3", leftToes = "leg_joint_L_5",
}

local function fails(opts, needle)
  local ok, err = pcall(troupe.actor, opts)
  expect(not ok, "troupe.actor should fail for " .. tostring(opts.name))
  expect(tostring(err):find(needle, 1, true) ~= nil,
    "the error names what is wrong: wanted `" .. needle .. "` in " .. tostring(err))
end

test("an actor dressed in CesiumMan acts as any other", function()
  local cesium = troupe.actor{ name = "cesium", look = CESIUM, bones = CESIUM_BONES, height = 1.6 }
  local plain = troupe.actor{ name = "plain", at = {1, 0, 0} }
  local wave = cesium:play(troupe.sequence{ name = "wave",
    r_shoulder_abduction = { {0, 0}, {0.5, 2.5} }, r_elbow_flexion = { {0, 0}, {0.5, 1} } })
  expect(wave:wait() == "completed", "the look changes nothing in the motion")
  expect(cesium.name == "cesium" and plain.name == "plain", "both actors are there")
end)

test("bad looks are errors that name the file and what is wrong", function()
  fails({ name = "a", look = "missing.glb" }, "missing.glb")
  fails({ name = "b", look = NO_SKIN }, "no skin")
  fails({ name = "c", look = CESIUM }, "no bone found for hips")
  fails({ name = "d", look = CESIUM, bones = { hips = "Pelvis" } }, "`hips` names `Pelvis`")
  fails({ name = "e", bones = CESIUM_BONES }, "give `look` too")
  fails({ name = "f", look = CESIUM, bones = { "Skeleton_torso_joint_1" } }, "pairs of strings")
  fails({ name = "g", look = CESIUM, bones = "hips" }, "expected a table")
  expect(troupe.get_actor("a") == nil, "a failed look adds no actor")
end)
