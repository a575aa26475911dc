-- A VMC performer hands a cup to an autonomous actor. Pat is driven by a VMC stream
-- (replayed from vmc_handover.rec, which scripts/vmc/record_handover.sh recorded from a
-- second troupe sending over VMC; a live sender works the same with listen =
-- "0.0.0.0:39540"): she takes the cup (floating, no table under it) and holds it out. The stream's
-- finger bones close her right hand through the grasping automaton, so she holds the cup.
-- Bob sees it, takes it with receive{from = pat}, and Pat opens her hand.
-- Run: troupe run scripts/examples/vmc_handover.lua --seconds 12
local pat = troupe.performer{ name = "pat",
  devices = { vmc = { replay = "vmc_handover.rec", hand = "right" } } }
local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1, at = {-0.2, 1.0, 0.38} }
pat:capture{}

local last = "FREE_HAND"
pat:behave(function(self)
  while troupe.time() < 11 do
    local state, object = troupe.devices.hand_state(self)
    if state ~= last then
      print(string.format("%.2f s: pat's hand %s%s", troupe.time(), state,
                          object and (" (" .. object .. ")") or ""))
      last = state
    end
    wait(0.01)
  end
end)

bob:behave(function(self)
  wait_until(function() return cup.holder == pat end, 10)
  wait(0.5)
  local rx = self:receive{ object = cup, from = pat }
  print("receive: " .. rx:wait() .. (rx.error and (" (" .. rx.error .. ")") or "")
        .. ", the cup is held by " .. (cup.holder and cup.holder.name or "nobody"))
end)
