-- The 1.2 m corridor of avoidance.lua and collision.lua (require("support.corridor")):
-- two walls 1.3 m apart along z (inner faces at x = ±0.6), Ann at one end and Bob at the
-- other, 8 m apart. Returns Ann, Bob and their walks, each to the other's end.
return function()
  troupe.wall{ from = {-0.65, -1}, to = {-0.65, 9}, thickness = 0.1 }
  troupe.wall{ from = {0.65, -1}, to = {0.65, 9}, thickness = 0.1 }
  local ann = troupe.actor{ name = "ann", at = {0, 0, 0} }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 8}, facing = 180 }
  return ann, bob, { ann:walk{ to = {0, 0, 8} }, bob:walk{ to = {0, 0, 0} } }
end
