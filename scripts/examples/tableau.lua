-- A tableau vivant: five performers walk into poses and hold them, one waving.
-- Render it: troupe render scripts/examples/tableau.lua docs/images/troupe.png --at 1.5 \
--              --size 1000x450 --camera fit@12,8 --no-labels
local d = math.rad

-- Each pose is a sequence that eases from rest into the pose and holds it.
local function strike(pose, seconds)
  ---@type table<string, any>
  local tracks = { name = "pose" }
  for dof, degrees in pairs(pose) do
    tracks[dof] = { {0, 0}, {seconds, d(degrees)}, {seconds + 10, d(degrees)} }
  end
  return troupe.sequence(tracks)
end

local poses = {
  { r_shoulder_abduction = 150, r_elbow_flexion = 70, l_shoulder_abduction = 10, skullbase_torsion = -15 },
  { l_hip_flexion = 30, r_hip_flexion = -15, r_knee_flexion = 35, l_knee_flexion = 10,
    l_shoulder_flexion = -25, r_shoulder_flexion = 30, r_elbow_flexion = 35, l_elbow_flexion = 20 },
  { r_shoulder_flexion = 80, l_shoulder_flexion = 70, r_elbow_flexion = 20, l_elbow_flexion = 25, vl5_flexion = 20,
    r_index1_flexion = 60, r_index2_flexion = 70, r_middle1_flexion = 60, r_middle2_flexion = 70 },
  { vl5_flexion = 45, vt12_flexion = 25, l_shoulder_flexion = 50, r_shoulder_flexion = 30, skullbase_flexion = -25 },
  { l_shoulder_abduction = 90, r_shoulder_abduction = 90, skullbase_torsion = 30, vc4_lateral_bend = 10 },
}
local facing = { 25, -10, -35, 40, -10 }

for i, pose in ipairs(poses) do
  local actor = troupe.actor{ name = "performer" .. i, template = i == 4 and "child" or "adult",
                              at = { (i - 3) * 1.1, 0, 0 }, facing = facing[i] }
  actor:behave(function(self)
    self:play(strike(pose, 1.0)):wait()
  end)
end

-- The first performer waves while holding the pose.
assert(troupe.get_actor("performer1")):behave(function(self)
  wait(1.0)
  self:play("wave.trk", { mode = "weighted", weight = 0.4, scope = "r_elbow+r_wrist", ease_in = 0.3 })
end)
