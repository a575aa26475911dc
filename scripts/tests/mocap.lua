-- Real motion capture plays on a troupe actor: a BVH file is retargeted on load.
local walk = "../../../shared/data/bvh/pybvhrepo_cmu_12_01_walk.bvh"

test("a CMU walk BVH plays on an adult and moves the legs", function()
  local ann = troupe.actor{ name = "ann" }
  local a = ann:play(walk, { scope = "legs+arms+spine" })
  local knee_min, knee_max = math.huge, -math.huge
  for _ = 1, 200 do
    run(0.01)
    local k = ann:dof("l_knee_flexion")
    knee_min, knee_max = math.min(knee_min, k), math.max(knee_max, k)
  end
  expect(a.status == "active", "still playing: " .. a.status)
  expect(knee_max - knee_min > 0.5, "the knee swings by more than 0.5 rad: " .. (knee_max - knee_min))
  a:cancel()
end)

test("a retargeted BVH is also a sequence value", function()
  local s = troupe.sequence(walk)
  expect(s.duration > 4 and s.duration < 5, "about 4.4 s: " .. s.duration)
  expect(#s:dofs() > 30, "many DOFs")
end)

test("a recording of several actors plays each actor's own part, or the part named", function()
  local recording = "support/two_parts.trk"   -- ann waves, bob nods
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {1, 0, 0} }
  local carl = troupe.actor{ name = "carl", at = {2, 0, 0} }
  local wave, nod = ann:play(recording), bob:play(recording)
  local also = carl:play(recording, { part = "bob" })
  run(1)
  expect(ann:dof("r_shoulder_abduction") > 1.5, "ann waves: " .. ann:dof("r_shoulder_abduction"))
  expect(bob:dof("r_shoulder_abduction") == 0 and bob:dof("skullbase_flexion") ~= 0, "bob nods")
  expect(carl:dof("skullbase_flexion") == bob:dof("skullbase_flexion"), "carl nods bob's part")
  for _, a in ipairs({ wave, nod, also }) do a:cancel() end
  local dee = troupe.actor{ name = "dee", at = {3, 0, 0} }
  local ok, e = pcall(function() return dee:play(recording) end)
  expect(not ok and tostring(e):find("records 2 actors (ann, bob), none of them `dee`: choose one with `part = …`", 1, true),
         tostring(e))
end)
