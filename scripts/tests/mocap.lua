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
