-- The standard library modules load with require and produce playable sequences.
local gestures = require("gestures")

test("require loads scripts/lib modules once", function()
  expect(require("gestures") == gestures, "the same module table")
  local ok, err = pcall(require, "../secrets")
  expect(not ok and tostring(err):find("invalid module name") ~= nil, tostring(err))
  ok, err = pcall(require, "nonexistent")
  expect(not ok and tostring(err):find("not found") ~= nil, tostring(err))
end)

test("a bow bends the spine and comes back", function()
  local ann = troupe.actor{ name = "ann" }
  local bow = ann:play(gestures.bow(0.5, 1.5))
  run(0.75)
  expect(ann:dof("vl5_flexion") > 0.4, "bent at mid-bow: " .. ann:dof("vl5_flexion"))
  expect(bow:wait() == "completed", "completes")
  expect(math.abs(ann:dof("vl5_flexion")) < 1e-9, "upright again")
end)

test("look_toward turns the head to the left for a point on the left", function()
  local ann = troupe.actor{ name = "ann" }   -- faces +Z; its left is +X
  run(0.01)
  local look = ann:play(gestures.look_toward(ann, {3, 1.6, 1}, 0.5))
  run(0.1)
  expect(ann:dof("skullbase_torsion") > 0.3, "head turned left: " .. ann:dof("skullbase_torsion"))
  look:wait()
end)
