-- A busy plaza: four streams of 50 actors cross a 20 m × 20 m square with a planter near
-- each corner (issue 18; docs/navigation.md, "The plaza"). Every walk must end at its
-- goal within TIME_BOUND; the test prints the worst interpenetration of solids and of
-- body discs and the mean detour (walked / straight − 1), and bounds them at what the
-- walkers do today, so that a change that makes them worse fails. Today every walker
-- arrives, by 147 s, every pelvis above 0.81 m, and no two solids meet (discs by 0.001
-- m); in the other layouts limbs still meet by up to 0.028 m (feet on feet, a foot or a
-- shin in a planter), eight to ten of twelve within 1 cm, short of issue 18's 1 cm
-- (docs/navigation.md, Limits). The bounds on the time, the solids, the discs and the
-- detour are the largest of any layout in any draw measured (docs/navigation.md,
-- "Landings round corners, stalled bodies, slivers of mesh" and "Feet held whole"),
-- rounded up, not this layout's own figures, which are one draw of a chaotic scene: the
-- change before this one drew 153.8 s, 0.029 m and 17.6 % here and 137.0 s, 0.018 m and
-- 14.5 % before that, and other draws of no change put walkers past 150 s and the
-- detour at 25.9 %. It needs
-- more than the default 120 simulated seconds (its own timeout below) and three to five
-- minutes of the debug build a run
-- (docs/navigation.md, "Cost"). The scene is chaotic: a change that alters one walker's
-- step in a rare case moves the worst figures by half (0.059 m of solids became 0.088 m,
-- its discs 0.033 m became 0 with one such change), so a change that moves them
-- re-measures, on several layouts, and says so: scripts/tests/support/plaza_layouts.lua
-- (docs/navigation.md, "Measuring a change on twelve layouts", which also gives how far a
-- change that changes nothing moves this layout's figures: the bounds below can fail on
-- such a draw, as arrivals and discs did in one). Where and why walkers stand:
-- scripts/tests/support/plaza_jam.lua.
local plaza = require("support.plaza_streams")

-- Seconds by which every walk must have ended: walkers of several layouts and draws were
-- still walking at 150 s, and in a draw of no change since the swinging feet keep off the
-- others' feet (docs/navigation.md, "Hands kept in, feet kept off feet") this layout's
-- last walker arrived at 183.6 s.
local TIME_BOUND = 200
-- Deepest interpenetration (m) allowed: of two actors' solids or a solid and a planter
-- (0.028 m the deepest of any layout in two draws since a foot held in the air is held
-- whole; 0.078 m before, and 0.094 m in older draws of no change), and of two body
-- discs (0.034 m the deepest of any layout in the draws of no change; this layout's own
-- went from 0 to 0.015 m when the obstacles' inflation changed by millimetres).
local SOLIDS_BOUND = 0.05
local DISCS_BOUND = 0.035
-- Mean detour allowed: 26.0 % the most of any layout in any draw (that same draw).
local DETOUR_BOUND = 0.27
-- Deepest a thigh may go into a planter, of the contacts sampled (m): the knees keep off
-- the furniture (docs/navigation.md, "Knees kept off the furniture"); before they did, a
-- thigh was this layout's deepest contact, 0.056 m into a planter.
local THIGH_BOUND = 0.01
-- Lowest a walker's pelvis (its root, 0.96 m up standing) may go: walkers whose body went
-- on from a planted foot sank it to the floor (0.10 m) before the walk held them back.
local PELVIS_BOUND = 0.72

test("four streams of 50 cross a plaza: everyone arrives", function()
  local actors, walks, goals, walked, straight = {}, {}, {}, {}, {}
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
  local solids, discs, thighs, tick = { 0, "nothing" }, { 0, "nothing" }, { 0, "nothing" }, 0
  local lowest = { math.huge, "nobody" }
  local function deeper(worst, d, a, b, sa, sb)
    if d > worst[1] then
      worst[1] = d
      worst[2] = string.format("%s's %s and %s%s", a, sa or "disc", b, sb and ("'s " .. sb) or "")
    end
  end
  local ok = run_until(function()
    tick = tick + 1
    for i, a in ipairs(actors) do
      local p = a:position()
      walked[i] = walked[i] + math.sqrt((p[1] - last[i][1])^2 + (p[3] - last[i][3])^2)
      last[i] = p
    end
    -- Bodies move less than 7 cm in 5 ticks: checking every fifth tick is enough.
    if tick % 5 == 0 then
      local d, a, b, sa, sb = troupe.deepest_overlap()
      deeper(solids, d, a, b, sa, sb)
      if sb == nil and sa and sa:find("thigh") then deeper(thighs, d, a, b, sa, sb) end
      deeper(discs, troupe.deepest_overlap{ discs = true })
      for _, a in ipairs(actors) do
        local y = a:position()[2]
        if y < lowest[1] then lowest[1], lowest[2] = y, a.name end
      end
    end
    return plaza.ended(walks)
  end, TIME_BOUND)
  local arrived, detour = plaza.tally(walks, walked, straight)
  print(string.format("plaza: %d of %d arrived by t = %.1f s; deepest solids %.3f m (%s), discs %.3f m (%s); mean detour %.1f %%; lowest pelvis %.3f m (%s)",
    arrived, #actors, troupe.time(), solids[1], solids[2], discs[1], discs[2], 100 * detour, lowest[1], lowest[2]))
  expect(ok, "every walk ended within " .. TIME_BOUND .. " s")
  expect(arrived == #actors, arrived .. " of " .. #actors .. " arrived")
  for i, a in ipairs(actors) do
    local p = a:position()
    local miss = math.sqrt((p[1] - goals[i][1])^2 + (p[3] - goals[i][2])^2)
    expect(miss < 0.1, string.format("%s stopped %.2f m from its goal", a.name, miss))
  end
  expect(solids[1] <= SOLIDS_BOUND, string.format("solids interpenetrated %.3f m", solids[1]))
  expect(thighs[1] <= THIGH_BOUND, string.format("a thigh went %.3f m into a planter (%s)", thighs[1], thighs[2]))
  expect(discs[1] <= DISCS_BOUND, string.format("discs interpenetrated %.3f m", discs[1]))
  expect(detour <= DETOUR_BOUND, string.format("mean detour %.1f %%", 100 * detour))
  expect(lowest[1] >= PELVIS_BOUND, string.format("%s's pelvis sank to %.3f m", lowest[2], lowest[1]))
end, { timeout = TIME_BOUND + 10 })
