-- Two actors meet: Ann waves at Bob while she turns her head to him, Bob nods back,
-- then both bow together. Run: troupe run scripts/examples/greeting.lua
local gestures = require("gestures")
local ann = troupe.actor{ name = "ann", template = "adult", height = 1.65, at = {-0.8, 0, 0}, facing = 90 }
local bob = troupe.actor{ name = "bob", template = "adult", height = 1.82, at = { 0.8, 0, 0}, facing = -90 }
troupe.object{ name = "table", shape = "box", size = {1.2, 0.75, 0.6}, at = {0, 0.375, 1.2}, mass = 20 }

local bow = troupe.sequence{
  vl5_flexion       = { {0, 0}, {0.8, 0.45}, {1.6, 0.45}, {2.4, 0} },
  vt12_flexion      = { {0, 0}, {0.8, 0.2},  {1.6, 0.2},  {2.4, 0} },
  skullbase_flexion = { {0, 0}, {0.8, 0.3},  {1.6, 0.3},  {2.4, 0} },
}

ann:behave(function(self)
  -- Look toward Bob's head (a weighted turn that eases in and out around the wave).
  local look = self:play(gestures.look_toward(self, bob:joint_position("skullbase"), 3),
                         { mode = "weighted", weight = 0.8, ease_in = 0.4, ease_out = 0.4 })
  local wave = self:play("wave.trk", { scope = "right_arm", ease_in = 0.3, ease_out = 0.3 })
  print("waving at " .. bob.name)
  wait_all(wave, look)
  self:play(bow):wait()
  print("done at t = " .. troupe.time())
end)

bob:behave(function(self)
  wait(0.8)
  local nod = self:play("nod.trk", { ease_in = 0.1, ease_out = 0.1 })
  if nod:wait() ~= "completed" then print("nod ended as " .. nod.status) end
  wait_until(function() return troupe.time() >= 3.0 end, 5)
  self:play(bow):wait()
end)
