-- A seeded crowd: 24 actors on a grid, each running its own randomized loop of gestures
-- (weighted waves, nods, bows), cancelling some of them early.
-- Run: troupe run scripts/examples/crowd.lua --seconds 20 --threads 2 --seed 7
local wave = troupe.sequence("wave.trk")
local nod = troupe.sequence("nod.trk")
local bow = troupe.sequence{ vl5_flexion = { {0, 0}, {0.5, 0.4}, {1.0, 0} } }

for i = 0, 23 do
  local actor = troupe.actor{
    name = "walker" .. i,
    template = (i % 4 == 3) and "child" or "adult",
    height = (i % 4 == 3) and 1.2 + math.random() * 0.2 or 1.6 + math.random() * 0.3,
    at = { (i % 6) * 1.2, 0, (i // 6) * 1.5 },
    facing = math.random(0, 359),
  }
  actor:behave(function(self)
    wait(math.random() * 2)
    while true do
      local r = math.random()
      local a
      if r < 0.4 then
        a = self:play(wave, { mode = "weighted", weight = 0.5 + 0.5 * math.random(), ease_in = 0.3, ease_out = 0.3, scope = "right_arm" })
      elseif r < 0.8 then
        a = self:play(nod, { ease_in = 0.1, ease_out = 0.1 })
      else
        a = self:play(bow, { mode = "exclusive", ease_in = 0.2, ease_out = 0.2 })
      end
      if math.random() < 0.25 then
        wait(0.5)
        a:cancel()
      end
      a:wait()
      wait(0.2 + math.random())
    end
  end)
end
