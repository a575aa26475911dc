-- A character of your own: Khronos' glTF sample model CesiumMan (© 2017 Cesium, CC-BY
-- 4.0; tests/assets/characters/) dressed on an adult, beside an actor in troupe's
-- generated skin; both wave and turn their heads. Run: troupe run scripts/examples/character.lua --view
local gestures = require("gestures")

-- CesiumMan's joints have names of their own: the map names them by VRM humanoid bones.
local cesium = troupe.actor{ name = "cesium", height = 1.75, at = {-0.55, 0, 0}, facing = 15,
  look = "../../tests/assets/characters/CesiumMan.glb",
  bones = {
    hips = "Skeleton_torso_joint_1", spine = "Skeleton_torso_joint_2",
    upperChest = "torso_joint_3", neck = "Skeleton_neck_joint_1", head = "Skeleton_neck_joint_2",
    leftUpperArm = "Skeleton_arm_joint_L__4_", leftLowerArm = "Skeleton_arm_joint_L__3_",
    leftHand = "Skeleton_arm_joint_L__2_", rightUpperArm = "Skeleton_arm_joint_R",
    rightLowerArm = "Skeleton_arm_joint_R__2_", rightHand = "Skeleton_arm_joint_R__3_",
    leftUpperLeg = "leg_joint_L_1", leftLowerLeg = "leg_joint_L_2", leftFoot = "leg_joint_L_3",
    leftToes = "leg_joint_L_5", rightUpperLeg = "leg_joint_R_1", rightLowerLeg = "leg_joint_R_2",
    rightFoot = "leg_joint_R_3", rightToes = "leg_joint_R_5",
  } }
local ann = troupe.actor{ name = "ann", height = 1.7, at = {0.55, 0, 0}, facing = -15 }

for _, actor in ipairs({ cesium, ann }) do
  actor:behave(function(self)
    local other = self == cesium and ann or cesium
    local look = self:play(gestures.look_toward(self, other:joint_position("skullbase"), 3),
                           { mode = "weighted", weight = 0.8, ease_in = 0.4, ease_out = 0.4 })
    local wave = self:play("wave.trk", { scope = "right_arm", ease_in = 0.3, ease_out = 0.3 })
    wait_all(wave, look)
  end)
end
