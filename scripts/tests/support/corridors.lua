-- Two groups meeting head-on in corridors of several widths, to measure a change to
-- stand-offs (docs/navigation.md, "Stand-offs"): each scene prints one line, how many
-- arrived and when, the longest any walker stood still on the way, and the deepest
-- interpenetration of solids. It checks nothing. Release build, two at a time (about
-- 40 s on this kind of machine):
--   troupe test scripts/tests/support/corridors.lua --shard 1/2 &
--   troupe test scripts/tests/support/corridors.lua --shard 2/2
-- A scene is a corridor `width` m wide (walls along z from −6 to 6 m), `n` walkers a
-- side in rows 0.9 m apart of as many abreast as fit 0.65 m apart, the first rows 7 m
-- apart, each bound 8 m beyond the middle (0.9 m more a row back), the goals `spread` m
-- apart.
local function scene(name, width, n, spread)
  test(name, function()
    local h = width / 2 + 0.1
    troupe.wall{ from = { -h, -6 }, to = { -h, 6 }, thickness = 0.2, height = 2 }
    troupe.wall{ from = { h, -6 }, to = { h, 6 }, thickness = 0.2, height = 2 }
    local actors, walks = {}, {}
    local cols = math.max(1, math.floor((width - 0.3) / 0.65))
    for i = 1, 2 * n do
      local side = i <= n and -1 or 1
      local k = (i - 1) % n
      local col, row = k % cols, k // cols
      local x = (col - (cols - 1) / 2) * 0.65
      local z = side * (3.5 + row * 0.9)
      actors[i] = troupe.actor{ name = (side < 0 and "a" or "b") .. (k + 1), at = { x, 0, z }, facing = side < 0 and 0 or 180 }
      local gx = (k - (n - 1) / 2) * spread
      walks[i] = actors[i]:walk{ to = { gx, 0, -side * (8 + row * 0.9) } }
    end
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
