-- The stand-off scenes of scripts/tests/avoidance.lua and composing.lua with their
-- walkers' starts moved by a millimetre to 20 cm, to measure whether they pass by rule
-- or by chance (docs/navigation.md, "Stand-offs"): two pairs in a 1.6 m corridor and two
-- groups of five in a 2.3 m one (the first rows moved), three a side at a 1.6 m doorway
-- in a wall (one walker of either side moved across), two waiters with trays in aisles
-- of 1.6 and 1.55 m and a tray in one hand meeting a walker in a 1.4 m aisle (ann moved
-- across). Each variant is one test printing one line: how many arrived and by when,
-- the deepest interpenetration of solids from a second into the walks, and the walks
-- that did not end well. It checks nothing (every variant counts as passed):
--   troupe test scripts/tests/support/stand_offs.lua | grep RESULT
local groups = require("corridor_groups")

local MOVED = { 0.001, -0.002, 0.003, 0.01, -0.01, 0.03, -0.05, 0.05, 0.07, -0.07, 0.1, -0.1, 0.15, -0.15, 0.2, -0.2 }

-- Runs until every walk has ended (90 s at most) and prints the scene's line.
local function report(label, actors, walks)
  local start, solids, what = troupe.time(), 0.0, ""
  run_until(function()
    local d, a, b, sa = troupe.deepest_overlap()
    if troupe.time() - start > 1 and d > solids then
      solids, what = d, string.format(" (%s's %s and %s at %.1f s)", tostring(a), tostring(sa), tostring(b), troupe.time())
    end
    for _, w in ipairs(walks) do if w.status == "active" then return false end end
    return true
  end, 90)
  local arrived, ill = 0, {}
  for i, w in ipairs(walks) do
    if w.status == "completed" then arrived = arrived + 1
    else ill[#ill + 1] = string.format("%s %s: %s", actors[i].name, w.status, tostring(w.error)) end
  end
  print(string.format("RESULT %-26s %2d of %2d by %5.1f s, solids %.4f m%s%s", label, arrived, #walks,
    troupe.time() - start, solids, solids > 0.01 and what or "", #ill > 0 and "; " .. table.concat(ill, "; ") or ""))
end

-- The doorway of avoidance.lua, `which` side's first walker (s1 or n1) moved by `dx`.
local function doorway(which, dx)
  troupe.wall{ from = {-8, 0}, to = {-0.8, 0} }
  troupe.wall{ from = {0.8, 0}, to = {8, 0} }
  local actors, walks = {}, {}
  for i = 1, 3 do
    local x = -2.25 + (i - 1) * 1.5
    local ds, dn = which == "s" and i == 1 and dx or 0, which == "n" and i == 1 and dx or 0
    actors[#actors + 1] = troupe.actor{ name = "s" .. i, at = {x + ds, 0, -2.5 - 0.3 * i}, facing = 0 }
    walks[#actors] = actors[#actors]:walk{ to = {x, 0, 4.5} }
    actors[#actors + 1] = troupe.actor{ name = "n" .. i, at = {-x + dn, 0, 2.5 + 0.3 * i}, facing = 180 }
    walks[#actors] = actors[#actors]:walk{ to = {-x, 0, -4.5} }
  end
  return actors, walks
end

-- The aisle of composing.lua (`width` m, stands and trays beyond its ends), ann moved
-- across by `dx`, the hands `hands[i]` carrying.
local function aisle(width, hands, dx)
  troupe.wall{ from = {-width / 2, -4}, to = {-width / 2, 4}, thickness = 0.1 }
  troupe.wall{ from = {width / 2, -4}, to = {width / 2, 4}, thickness = 0.1 }
  local people, actors, walks = {}, {}, {}
  for i, side in ipairs({ -1, 1 }) do
    local name = i == 1 and "ann" or "bob"
    local a = troupe.actor{ name = name, at = {i == 1 and dx or 0, 0, 6 * side}, facing = side < 0 and 0 or 180 }
    troupe.object{ name = "stand_" .. name, shape = "box", size = {0.5, 0.8, 0.4}, at = {0, 0.4, 5.4 * side}, mass = 20 }
    local tray = troupe.object{ name = "tray_" .. name, shape = "box", size = {0.4, 0.03, 0.3},
                                at = {0, 0.815, 5.4 * side}, mass = 1 }
    people[i], actors[i] = { tray = tray, goal = {0, 0, -7 * side} }, a
  end
  for i, a in ipairs(actors) do
    if hands[i] then a:grasp{ object = people[i].tray, hand = hands[i] }:wait() end
  end
  for i, a in ipairs(actors) do walks[i] = a:walk{ to = people[i].goal } end
  return actors, walks
end

for _, d in ipairs(MOVED) do
  test("two pairs, 1.6 m corridor, moved " .. d, function()
    local actors, walks = groups(1.6, 2, 0.8, 0.6, 4 + d)
    report("pairs 1.6 m " .. d, actors, walks)
  end)
  test("two groups of five, 2.3 m corridor, moved " .. d, function()
    local actors, walks = groups(2.3, 5, 0.7, 0.6, 4 + d)
    report("five 2.3 m " .. d, actors, walks)
  end)
  for _, which in ipairs({ "s", "n" }) do
    test("doorway, " .. which .. "1 moved " .. d, function()
      local actors, walks = doorway(which, d)
      report("doorway " .. which .. "1 " .. d, actors, walks)
    end)
  end
  test("trays, 1.6 m aisle, moved " .. d, function()
    report("trays 1.6 m " .. d, aisle(1.6, { "both", "both" }, d))
  end)
  test("trays, 1.55 m aisle, moved " .. d, function()
    report("trays 1.55 m " .. d, aisle(1.55, { "both", "both" }, d))
  end)
  test("a tray and a walker, 1.4 m aisle, moved " .. d, function()
    report("one tray 1.4 m " .. d, aisle(1.4, { "right" }, d))
  end)
end
