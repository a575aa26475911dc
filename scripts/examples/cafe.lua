-- A café (issue 16: actions that compose). The waiter walks to the counter and picks up
-- a cup, carries it past a standing guest (the walk brings it in to the body and carries
-- it upright) to a second guest, and hands it over; the guest drinks, lifting the cup to
-- the mouth, and puts it down on the bar table beside her. No action fails.
-- Run: troupe run scripts/examples/cafe.lua --until-idle
local waiter = troupe.actor{ name = "waiter" }
local standing = troupe.actor{ name = "standing_guest", at = {1.6, 0, 1.0}, facing = -30 }
local guest = troupe.actor{ name = "guest", at = {3.0, 0, 3.0}, facing = 180 }
troupe.object{ name = "counter", shape = "box", size = {1.2, 0.95, 0.4}, at = {0, 0.475, 2.62}, mass = 60 }
troupe.object{ name = "bar_table", shape = "box", size = {0.4, 0.95, 0.5}, at = {3.6, 0.475, 2.75}, mass = 15 }
local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                           at = {-0.2, 1.0, 2.45}, mass = 0.3 }
local served = false

local function report(what, a)
  local status = a:wait()
  if status ~= "completed" then print(what .. ": " .. status .. " (" .. tostring(a.error) .. ")") end
  return status
end

waiter:behave(function(self)
  report("walk to the counter", self:walk{ to = {0, 0, 2.0}, heading = 0, speed = 1.0 })
  report("pick up the cup", self:grasp{ object = cup, hand = "right", duration = 0.8 })
  -- Past the standing guest, to face the guest across the hand-over distance.
  report("carry", self:walk{ path = {{1.0, 1.9}, {3.0, 2.1}}, heading = 0, speed = 1.0 })
  report("hand over", self:give{ object = cup, to = guest, hand = "right" })
  served = true
  report("walk back", self:walk{ to = {0.5, 0, 0.5}, speed = 1.0 })
end)

standing:behave(function(self)
  self:look_at{ target = waiter, duration = 9, ease_in = 0.5, ease_out = 0.5 }
end)

guest:behave(function(self)
  wait_until(function() return served end, 30)
  local mouth = self:joint_position("skullbase")
  local p = cup:position()
  report("drink", self:manipulate{ object = cup, keys = {
    { t = 1.0, at = {mouth[1] + 0.02, mouth[2] - 0.1, mouth[3] - 0.12} },
    { t = 1.8, at = {mouth[1] + 0.02, mouth[2] - 0.1, mouth[3] - 0.12} },
    { t = 2.6, at = p },
  } })
  report("put it down", self:place{ object = cup, at = {3.42, 1.0, 2.8}, duration = 1.0 })
  print(string.format("the cup is on the bar table at t = %.2f s", troupe.time()))
end)
