-- Two actors hand over a cup (thesis 4.5): Ann picks it up from the table and gives it
-- to Bob, who takes it with his right hand and lifts it; then Bob offers his left hand
-- and Ann shakes it. Run: troupe run scripts/examples/handover.lua --until-idle
local ann = troupe.actor{ name = "ann" }
local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
troupe.object{ name = "table", shape = "box", size = {0.6, 0.95, 0.3}, at = {-0.45, 0.475, 0.45}, mass = 20 }
local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1, at = {-0.2, 1.0, 0.38} }
local offered = false

ann:behave(function(self)
  self:grasp{ object = cup, hand = "right" }:wait()
  local give = self:give{ object = cup, to = bob, hand = "right" }
  print("give: " .. give:wait() .. ", the cup is held by " .. (cup.holder and cup.holder.name or "nobody"))
  wait_until(function() return offered end, 10)
  local s = self:shake_hands{ other = bob, hand = "left", other_hand = "left" }
  print("handshake: " .. s:wait() .. (s.error and (" (" .. s.error .. ")") or ""))
end)

bob:behave(function(self)
  wait_until(function() return cup.holder == self end, 15)
  local p = cup:position()
  self:manipulate{ object = cup, keys = { { t = 0.8, at = {p[1], p[2] + 0.1, p[3] + 0.1} } } }:wait()
  print("bob lifted the cup to y = " .. string.format("%.2f", cup:position()[2]))
  offered = true   -- ann may shake his free hand now: he holds it out as she reaches
end)
