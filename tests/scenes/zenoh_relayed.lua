-- For tests/zenoh_cli.rs: a leader runs this scene with a glove served by `troupe relay`,
-- a follower runs it from the leader's replicated inputs, and a third run replays the
-- leader's --record-devices file; all three must compute the same postures bit for bit.
-- Two scripted actors: one uses the scene's random numbers and publishes a behavior
-- message after each reach, the other waits for a cue sent by a tool mid-run.
local pat = troupe.performer{ name = "pat", at = {-0.45, 0, 0.8}, facing = 180,
  devices = { glove = { zenoh = "troupe/devices/glove-replicated", hand = "right" } } }
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
    self:reach{ hand = "right", target = reach, duration = 0.5 }:wait()
    troupe.publish("ann/reached", { at = reach, tick = troupe.tick() })
  end
end)

bob:behave(function(self)
  wait_until(function() return cue ~= nil end, 60)
  local dof = cue.side == "left" and "l_elbow_flexion" or "r_elbow_flexion"
  self:play(troupe.sequence{ [dof] = { {0, 0}, {1, cue.angle}, {2, 0} } }):wait()
end)
