-- For tests/zenoh_cli.rs: a leader and a follower run this scene and must compute the
-- same postures bit for bit: a performer whose glove is replayed from a recording, two
-- scripted actors that use the scene's random numbers, and a remote message that changes
-- what one of them does.
local pat = troupe.performer{ name = "pat", at = {-0.45, 0, 0.8}, facing = 180,
  devices = { glove = { replay = "../../scripts/examples/performer_handover_glove.rec", hand = "right" } } }
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
    self:reach{ hand = "right", target = reach, duration = 0.8 }:wait()
    troupe.publish("ann/reached", { at = reach, tick = troupe.tick() })
  end
end)

bob:behave(function(self)
  wait_until(function() return cue ~= nil end, 60)
  -- The cue says which elbow to bend, and how far.
  local dof = cue.side == "left" and "l_elbow_flexion" or "r_elbow_flexion"
  self:play(troupe.sequence{ [dof] = { {0, 0}, {1, cue.angle}, {2, 0} } }):wait()
  self:walk{ to = {-0.6, -0.5}, speed = 0.6 }:wait()
end)
