-- The cast of zenoh_follow.lua and zenoh_relayed.lua: a performer whose right glove is
-- `glove` (a device table), and two scripted actors whose motion depends on what a
-- follower must replicate. Ann reaches for points from the scene's random numbers (each
-- reach `reach_duration` s) and publishes a behavior message after each; Bob waits for
-- a cue sent by a tool mid-run, bends the elbow it names as far as it says, then walks
-- if `walk_after_cue`.
return function(glove, reach_duration, walk_after_cue)
  local pat = troupe.performer{ name = "pat", at = {-0.45, 0, 0.8}, facing = 180,
    devices = { glove = glove } }
  pat:play(troupe.sequence{ r_shoulder_flexion = { {0, 0.7}, {12, 0.7} },
                            r_elbow_flexion = { {0, 0.6}, {12, 0.6} } })
  pat:capture{}

  local ann = troupe.actor{ name = "ann", at = {0.6, 0, 0}, facing = -90 }
  local bob = troupe.actor{ name = "bob", at = {-0.6, 0, -0.8}, facing = 90 }
  local cue = nil
  troupe.subscribe("cue/**", function(value) cue = value end)

  ann:behave(function(self)
    while true do
      local reach = { math.random() * 0.6 - 0.3, 1.0 + math.random() * 0.4, 0.4 }
      self:reach{ hand = "right", target = reach, duration = reach_duration }:wait()
      troupe.publish("ann/reached", { at = reach, tick = troupe.tick() })
    end
  end)

  bob:behave(function(self)
    wait_until(function() return cue ~= nil end, 60)
    local dof = cue.side == "left" and "l_elbow_flexion" or "r_elbow_flexion"
    self:play(troupe.sequence{ [dof] = { {0, 0}, {1, cue.angle}, {2, 0} } }):wait()
    if walk_after_cue then self:walk{ to = {-0.6, -0.5}, speed = 0.6 }:wait() end
  end)
end
