-- The motion behind scripts/examples/vmc_handover.rec: an autonomous Pat takes the cup,
-- holds it out towards where Bob stands, and opens her hand at 7.5 s; her
-- posture goes out as a VMC stream (30 frames a second). The cup floats where a table
-- would hold it: a table under it would be touched by the fingers closing around it.
-- scripts/vmc/record_handover.sh runs it against a listening troupe that records the
-- stream; the example then replays it, with Pat a VMC performer and Bob an autonomous
-- actor who takes the cup.
local pat = troupe.actor{ name = "pat" }
local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1, at = {-0.2, 1.0, 0.38} }

pat:behave(function(self)
  self:grasp{ object = cup, hand = "right" }:wait()
  local p = cup:position()
  self:manipulate{ object = cup, duration = 1.2,
                   keys = { { t = 1.2, at = {p[1] + 0.15, p[2] + 0.1, p[3] + 0.22} } } }:wait()
  wait_until(function() return troupe.time() >= 7.5 end, 20)
  self:release{ object = cup }:wait()
  print(string.format("%.2f s: pat opened her hand", troupe.time()))
end)
