-- Walking hand in hand (thesis 4.5): Ann takes Bob's left hand with her right, then both
-- walk the same route side by side, their arms left to the hold: Ann's hand leads, Bob's
-- follows it by IK every tick. The script prints how far apart the two hands drifted.
-- Run: troupe run scripts/examples/hand_in_hand.lua --until-idle
local ann = troupe.actor{ name = "ann" }
local bob = troupe.actor{ name = "bob", at = {-0.45, 0, 0} }

local function gap()
  local a, b = ann:joint_position("r_wrist"), bob:joint_position("l_wrist")
  return math.sqrt((a[1] - b[1])^2 + (a[2] - b[2])^2 + (a[3] - b[3])^2)
end

ann:behave(function(self)
  local hold = self:hold_hand{ other = bob, hand = "right", other_hand = "left" }
  -- Let the hold close before setting off.
  wait(2.0)
  local held = gap()
  local worst = 0.0
  -- Same route, 45 cm apart, same pace; the walks leave the arms to the hold.
  local a = self:walk{ path = { {0, 2}, {1, 4}, {1, 6} }, speed = 1.0, arms = false }
  local b = bob:walk{ path = { {-0.45, 2}, {0.55, 4}, {0.55, 6} }, speed = 1.0, arms = false }
  while a.status ~= "completed" and a.status ~= "failed" do
    worst = math.max(worst, math.abs(gap() - held))
    wait(0.05)
  end
  b:wait()
  hold:cancel()
  print(string.format("walked hand in hand to z = %.2f; wrist gap %.3f m at the start, drifted at most %.1f mm",
    self:position()[3], held, worst * 1000))
end)
