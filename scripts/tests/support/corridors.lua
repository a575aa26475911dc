-- Two groups meeting head-on in corridors of several widths, to measure a change to
-- stand-offs (docs/navigation.md, "Stand-offs"): each scene prints one line, how many
-- arrived and when, the longest any walker stood still on the way, and the deepest
-- interpenetration of solids. It checks nothing. Release build, two at a time (about
-- 40 s on this kind of machine):
--   troupe test scripts/tests/support/corridors.lua --shard 1/2 &
--   troupe test scripts/tests/support/corridors.lua --shard 2/2
-- A scene is a corridor `width` m wide, `n` walkers a side 0.65 m apart abreast, the
-- first rows 7 m apart, the goals `spread` m apart (support/corridor_groups.lua).
local groups = require("corridor_groups")

local function scene(name, width, n, spread)
  test(name, function()
    local actors, walks = groups(width, n, spread, 0.65, 3.5)
    local t, solids, longest, still, last = 0, 0.0, 0.0, {}, {}
    for i, a in ipairs(actors) do local p = a:position(); last[i] = { p[1], p[3] }; still[i] = 0 end
    run_until(function()
      t = t + 1
      if t % 5 == 0 then solids = math.max(solids, (troupe.deepest_overlap())) end
      local all = true
      for i, a in ipairs(actors) do
        local p = a:position()
        local moved = math.sqrt((p[1] - last[i][1])^2 + (p[3] - last[i][2])^2)
        if walks[i].status == "active" and moved < 0.02 / troupe.rate() then
          still[i] = still[i] + 1 / troupe.rate(); longest = math.max(longest, still[i])
        else still[i] = 0 end
        last[i] = { p[1], p[3] }
        if walks[i].status ~= "completed" then all = false end
      end
      return all
    end, 90)
    local arrived = 0
    for _, w in ipairs(walks) do if w.status == "completed" then arrived = arrived + 1 end end
    print(string.format("RESULT %-28s %2d of %2d by %5.1f s, longest stand %5.1f s, solids %.3f m",
      name, arrived, 2 * n, troupe.time(), longest, solids))
  end, { timeout = 300 })
end
scene("w2.0 n2 spread1.0", 2.0, 2, 1.0)
scene("w2.0 n3 spread1.0", 2.0, 3, 1.0)
scene("w2.5 n4 spread1.0", 2.5, 4, 1.0)
scene("w2.5 n5 spread1.0", 2.5, 5, 1.0)
scene("w2.5 n5 spread0.7", 2.5, 5, 0.7)
scene("w3.0 n6 spread0.8", 3.0, 6, 0.8)
scene("w4.0 n8 spread0.8", 4.0, 8, 0.8)
scene("w1.6 n2 spread0.8", 1.6, 2, 0.8)
