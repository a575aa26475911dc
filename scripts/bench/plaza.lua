-- A busy plaza: four streams of 50 actors cross a 20 m × 20 m square with a few
-- obstacles in it (issue 18). KNOWN TO FAIL TODAY (docs/navigation.md, Limits): the
-- streams jam and bodies overlap; kept here as the measurement to make pass. Run it with
--   troupe test scripts/bench/plaza.lua
test("four streams of 50 cross a plaza: everyone arrives", function()
  -- Stream s starts in a 5 × 10 block outside one edge and goes to the opposite one.
  local actors, walks, goals, walked, straight = {}, {}, {}, {}, {}
  local plaza = require("plaza_streams")
  for i, w in ipairs(plaza.build(plaza.BUSY)) do
    actors[i] = w.actor
    goals[i] = { w.gx, w.gz }
    straight[i] = math.sqrt((w.gx - w.x)^2 + (w.gz - w.z)^2)
    walked[i] = 0
  end
  for i, a in ipairs(actors) do
    walks[i] = a:walk{ to = { goals[i][1], 0, goals[i][2] }, speed = 1.3 }
  end
  local last = {}
  for i, a in ipairs(actors) do last[i] = a:position() end
  local deepest, pair, tick = 0, "", 0
  local ok = run_until(function()
    tick = tick + 1
    for i, a in ipairs(actors) do
      local p = a:position()
      walked[i] = walked[i] + math.sqrt((p[1] - last[i][1])^2 + (p[3] - last[i][3])^2)
      last[i] = p
    end
    -- Bodies move less than 7 cm in 5 ticks: checking every fifth tick is enough.
    if tick % 5 == 0 then
      local d, x, y = troupe.deepest_overlap()
      if d > deepest then deepest, pair = d, x .. " and " .. y end
    end
    if tick % 1000 == 0 then
      local n = 0
      for _, w in ipairs(walks) do if w.status == "completed" then n = n + 1 end end
      print(string.format("t = %.0f s: %d arrived, deepest %.3f (%s)", troupe.time(), n, deepest, pair))
    end
    for _, w in ipairs(walks) do
      if w.status ~= "completed" and w.status ~= "failed" then return false end
    end
    return true
  end, 120)
  local detour, arrived = 0, 0
  for i, a in ipairs(actors) do
    if walks[i].status == "completed" then arrived = arrived + 1 end
    detour = detour + walked[i] / straight[i] - 1
  end
  print(string.format("plaza: %d of %d arrived by t = %.1f s; worst disc interpenetration %.4f m (%s); mean detour %.1f %%",
    arrived, #actors, troupe.time(), deepest, pair, 100 * detour / #actors))
  expect(ok, "every walk ended")
  expect(arrived == #actors, arrived .. " of " .. #actors .. " arrived")
  for i, a in ipairs(actors) do
    local p = a:position()
    local miss = math.sqrt((p[1] - goals[i][1])^2 + (p[3] - goals[i][2])^2)
    expect(miss < 0.1, string.format("%s stopped %.2f m from its goal", a.name, miss))
  end
  expect(deepest <= 0.01, string.format("bodies interpenetrated %.3f m", deepest))
end)
