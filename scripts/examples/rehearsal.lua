-- A rehearsal of the priority modes with three performers.
-- carla conducts: her arms beat a looping pattern while a weighted head sway blends in;
-- dan queues default actions that wait for each other; eve is interrupted by an
-- exclusive bow and finally a clearing "freeze".
-- Run: troupe run scripts/examples/rehearsal.lua --trace out/rehearsal.json
local carla = troupe.actor{ name = "carla", at = {0, 0, 1.5}, facing = 180 }
local dan   = troupe.actor{ name = "dan",   at = {-1.2, 0, 0} }
local eve   = troupe.actor{ name = "eve",   template = "child", at = {1.2, 0, 0} }

local beat = troupe.sequence{
  loop = true,
  r_shoulder_flexion = { {0, 0.6}, {0.5, 1.1}, {1.0, 0.6} },
  l_shoulder_flexion = { {0, 1.1}, {0.5, 0.6}, {1.0, 1.1} },
  r_elbow_flexion    = { {0, 1.2}, {0.5, 0.8}, {1.0, 1.2} },
  l_elbow_flexion    = { {0, 0.8}, {0.5, 1.2}, {1.0, 0.8} },
}
local sway = troupe.sequence{ loop = true, skullbase_lateral_bend = { {0, -0.15}, {1, 0.15}, {2, -0.15} } }
local bow  = troupe.sequence{ vl5_flexion = { {0, 0}, {0.6, 0.5}, {1.2, 0.5}, {1.8, 0} },
                              skullbase_flexion = { {0, 0}, {0.6, 0.3}, {1.2, 0.3}, {1.8, 0} } }
local freeze = troupe.sequence{ r_shoulder_abduction = { {0, 0.4}, {1, 0.4} },
                                l_shoulder_abduction = { {0, 0.4}, {1, 0.4} } }

carla:behave(function(self)
  local arms = self:play(beat, { ease_in = 0.5, ease_out = 0.5, duration = 6 })
  self:play(sway, { mode = "weighted", weight = 0.6, ease_in = 1, ease_out = 1, duration = 6 })
  arms:wait()
end)

dan:behave(function(self)
  -- Three default actions on overlapping scopes: each waits for the one before.
  local wave = self:play("wave.trk", { scope = "right_arm" })
  local b = self:play(bow)
  local again = self:play("wave.trk", { scope = "right_arm", ease_in = 0.2 })
  wait_all(wave, b, again)
end)

eve:behave(function(self)
  local w = self:play("wave.trk", { ease_out = 0.4 })
  wait(1.0)
  local b = self:play(bow, { mode = "exclusive", ease_in = 0.4, scope = "spine+head+right_arm" })
  print("wave ended as " .. w:wait() .. " (" .. tostring(w.error) .. ")")
  b:wait()
  self:play(freeze, { mode = "clearing", duration = 1.5, ease_in = 0.3, ease_out = 0.3 }):wait()
end)
