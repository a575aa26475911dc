-- Holding hands (thesis 4.5): Ann takes Bob's left hand with her right, then sways
-- forward and sideways by keyframes of her root while Bob's arm follows by IK, and lets
-- go. Run: troupe run scripts/examples/hold_hands.lua --until-idle
local ann = troupe.actor{ name = "ann" }
local bob = troupe.actor{ name = "bob", at = {-0.45, 0, 0} }

ann:behave(function(self)
  local hold = self:hold_hand{ other = bob, hand = "right", other_hand = "left" }
  wait_until(function() return troupe.time() > 2.0 end)
  local x = self:dof("root_x")
  local sway = troupe.sequence{ root_x = { {0, x}, {1, x + 0.06}, {2, x - 0.03}, {3, x} },
                                root_z = { {0, 0}, {1, 0.1}, {2, 0.15}, {3, 0} } }
  self:play(sway):wait()
  hold:cancel()
  for _, a in ipairs(bob:actions()) do a:cancel() end
  print("done at t = " .. troupe.time())
end)
