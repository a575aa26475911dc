-- Local avoidance between walkers (docs/navigation.md): they slow down, sidestep and
-- wait rather than overlap.

-- An adult's body radius (troupe_nav::body_radius): two discs closer than twice this
-- interpenetrate.
local RADIUS = 0.28

local function flat(p) return p[1], p[3] end

-- Runs until every walk in `walks` has ended (or `limit` s), watching the actors:
-- returns the deepest disc interpenetration, the longest time any walker stood still
-- more than 10 cm from its goal {x, z}, and whether all completed.
local function watch(actors, walks, goals, limit, each)
  local deepest, frozen, still = 0, 0, {}
  local last = {}
  for i, a in ipairs(actors) do last[i] = { flat(a:position()) }; still[i] = 0 end
  local dt = 1 / troupe.rate()
  local ok = run_until(function()
    if each then each() end
    local pos = {}
    for i, a in ipairs(actors) do pos[i] = { flat(a:position()) } end
    for i = 1, #actors do
      for j = i + 1, #actors do
        local d = math.sqrt((pos[i][1] - pos[j][1])^2 + (pos[i][2] - pos[j][2])^2)
        deepest = math.max(deepest, 2 * RADIUS - d)
      end
      local moved = math.sqrt((pos[i][1] - last[i][1])^2 + (pos[i][2] - last[i][2])^2)
      local away = math.sqrt((pos[i][1] - goals[i][1])^2 + (pos[i][2] - goals[i][2])^2) > 0.1
      if walks[i].status == "active" and away and moved < 0.02 * dt then
        still[i] = still[i] + dt
        frozen = math.max(frozen, still[i])
      else
        still[i] = 0
      end
      last[i] = pos[i]
    end
    for _, w in ipairs(walks) do
      if w.status ~= "completed" and w.status ~= "failed" then return false end
    end
    return true
  end, limit)
  return deepest, frozen, ok
end

test("eight actors on a circle swap to the opposite points", function()
  local actors, walks, goals = {}, {}, {}
  for i = 1, 8 do
    local a = (i - 1) * math.pi / 4
    local x, z = 3 * math.sin(a), 3 * math.cos(a)
    actors[i] = troupe.actor{ name = "a" .. i, at = {x, 0, z}, facing = math.deg(a) + 180 }
    goals[i] = { -x, -z }
  end
  for i, a in ipairs(actors) do
    walks[i] = a:walk{ to = { goals[i][1], 0, goals[i][2] }, speed = 1.2 }
  end
  local deepest, frozen, ok = watch(actors, walks, goals, 40)
  print(string.format("circle: deepest disc interpenetration %.4f m, longest stand %.2f s", deepest, frozen))
  expect(ok, "every walk ended")
  for i, a in ipairs(actors) do
    expect(walks[i].status == "completed", a.name .. ": " .. tostring(walks[i].error))
    local x, z = flat(a:position())
    local miss = math.sqrt((x - goals[i][1])^2 + (z - goals[i][2])^2)
    expect(miss < 0.05, string.format("%s stopped %.2f m from its goal", a.name, miss))
  end
  expect(deepest <= 0.01, string.format("bodies interpenetrated %.3f m", deepest))
  expect(frozen <= 3, string.format("someone stood still %.1f s", frozen))
end)

test("two actors head-on in a 1.2 m corridor pass each other", function()
  local ann, bob, walks = require("support.corridor")()
  -- The walls' inner faces are at x = ±0.6: the body's disc stays inside.
  local widest = 0
  local inner = function()
    for _, a in ipairs({ ann, bob }) do widest = math.max(widest, math.abs(a:position()[1])) end
  end
  local deepest, frozen, ok = watch({ ann, bob }, walks, { {0, 8}, {0, 0} }, 40, inner)
  print(string.format("corridor: deepest disc interpenetration %.4f m, longest stand %.2f s", deepest, frozen))
  expect(ok and walks[1].status == "completed" and walks[2].status == "completed",
    "both arrived: " .. tostring(walks[1].error) .. " / " .. tostring(walks[2].error))
  expect(ann:position()[3] > 7.7 and bob:position()[3] < 0.3, "they passed")
  print(string.format("corridor: widest %.3f m from the axis (wall at 0.6)", widest))
  expect(0.6 - widest >= RADIUS - 0.01, string.format("a body came %.3f m from a wall", 0.6 - widest))
  expect(deepest <= 0.01, string.format("bodies interpenetrated %.3f m", deepest))
  expect(frozen <= 3, string.format("someone stood still %.1f s", frozen))
end)

-- Runs `walks` of `actors` towards their `goals` {x, z} until every one has ended, and
-- checks that all arrive, with no bodies' discs or solids 1 cm into each other and, given
-- `longest`, nobody standing more than `longest` s; `label` names the scene's report line.
local function all_pass(label, actors, walks, goals, longest)
  local solids = 0.0
  local deepest, frozen, ok = watch(actors, walks, goals, 90, function()
    solids = math.max(solids, (troupe.deepest_overlap()))
  end)
  print(string.format("%s: all in by %.1f s; deepest discs %.4f m, solids %.4f m, longest stand %.2f s",
    label, troupe.time(), deepest, solids, frozen))
  expect(ok, "every walk ended")
  for i, a in ipairs(actors) do
    expect(walks[i].status == "completed", a.name .. ": " .. walks[i].status .. " " .. tostring(walks[i].error))
  end
  expect(deepest <= 0.01, string.format("discs interpenetrated %.3f m", deepest))
  expect(solids <= 0.01, string.format("solids interpenetrated %.3f m", solids))
  if longest then expect(frozen <= longest, string.format("someone stood still %.1f s", frozen)) end
end

-- Two groups meet head-on in a corridor `width` m wide, `n` a side 0.6 m apart abreast,
-- the first rows 8 m apart, their goals `spread` m apart (support/corridor_groups.lua):
-- all pass (see `all_pass`), nobody standing more than `longest` s.
local function groups_pass(label, longest, width, n, spread)
  local actors, walks, goals = require("support.corridor_groups")(width, n, spread, 0.6, 4)
  all_pass(label, actors, walks, goals, longest)
end

test("two pairs meet head-on in a 1.6 m corridor: one pair steps back and all pass", function()
  -- Four abreast do not fit: each walker stands face to face with one of the other
  -- pair, and nobody can step aside. Avoidance alone left all four standing for good;
  -- after 2 s the pair walking towards −z steps back (docs/navigation.md, "Stand-offs").
  groups_pass("two pairs in 1.6 m", 3, 1.6, 2, 0.8)
end)

test("two groups of five meet head-on in a 2.3 m corridor: they pass", function()
  -- Avoidance alone tied eight of them into a knot in the middle for good.
  groups_pass("two groups of five in 2.3 m", 5, 2.3, 5, 0.7)
end)

-- Three a side cross a 1.6 m doorway in a wall, the first from the south moved across by
-- `moved` m: all pass (see `all_pass`).
local function doorway_pass(label, moved)
  troupe.wall{ from = {-8, 0}, to = {-0.8, 0} }
  troupe.wall{ from = {0.8, 0}, to = {8, 0} }
  local actors, walks, goals = {}, {}, {}
  for i = 1, 3 do
    local x = -2.25 + (i - 1) * 1.5
    actors[#actors + 1] = troupe.actor{ name = "s" .. i, at = {x + (i == 1 and moved or 0), 0, -2.5 - 0.3 * i}, facing = 0 }
    goals[#actors] = {x, 4.5}
    actors[#actors + 1] = troupe.actor{ name = "n" .. i, at = {-x, 0, 2.5 + 0.3 * i}, facing = 180 }
    goals[#actors] = {-x, -4.5}
  end
  for i, a in ipairs(actors) do walks[i] = a:walk{ to = {goals[i][1], 0, goals[i][2]} } end
  all_pass(label, actors, walks, goals)
end

test("three a side cross a 1.6 m doorway in a wall: those before it step back and all pass", function()
  -- The doorway is a passage a wall's thickness long, crossed at a slant: the walkers
  -- wait before it, not in it, and their ways cross the door obliquely. Measured across
  -- the way where each stood, the passage was wider than 2.6 m, so nobody stepped back
  -- and all six stood for good (docs/navigation.md, "Stand-offs").
  doorway_pass("doorway", 0)
end)

test("the same with one walker moved by 3 cm: one pressed against the wall beside the door looks again before giving up", function()
  -- n3, pressed against the wall beside the door while the others came through, found
  -- only routes round the wall's far end (too long) and was to wait 16 s before looking
  -- again; the doorway cleared, and it gave up as stuck 4.9 m from its goal. A walk held
  -- with nobody moving near now looks again in its last 5 s before giving up
  -- (docs/navigation.md, "New routes round people standing in the way").
  doorway_pass("doorway, s1 moved", 0.03)
end)

test("someone standing in a doorway: after a wait the walker goes round by the other door", function()
  -- A way round three times as long as the straight way was never taken: the walker
  -- stood before the blocked doorway for good. A route may now be 1 m longer for each
  -- second waited.
  troupe.wall{ from = {-8, 3}, to = {-2.5, 3} }
  troupe.wall{ from = {-1.5, 3}, to = {3.5, 3} }
  troupe.wall{ from = {4.5, 3}, to = {8, 3} }
  troupe.actor{ name = "blocker", at = {-2.0, 0, 3.0} }
  local ann = troupe.actor{ name = "ann", at = {-2, 0, 0} }
  local w = ann:walk{ to = {-2, 0, 6} }
  local deepest = 0.0
  local ended = run_until(function()
    deepest = math.max(deepest, (troupe.deepest_overlap()))
    return w.status ~= "active"
  end, 60)
  print(string.format("round by the other door: %s at t = %.1f s, solids %.4f m", w.status, troupe.time(), deepest))
  expect(ended and w.status == "completed", w.status .. " " .. tostring(w.error))
  expect(deepest <= 0.01, string.format("solids %.3f m into each other", deepest))
end)

test("someone standing in a corridor: a walk with patience gives up naming them, a more patient one goes on when they leave", function()
  -- Two corridors 1.2 m wide, someone standing in the middle of each; in the second,
  -- the one standing walks off after 5 s.
  for _, x in ipairs({0, 5}) do
    troupe.wall{ from = {x - 0.6, -1}, to = {x - 0.6, 8} }
    troupe.wall{ from = {x + 0.6, -1}, to = {x + 0.6, 8} }
  end
  troupe.actor{ name = "blocker", at = {0, 0, 3} }
  local leaver = troupe.actor{ name = "leaver", at = {5, 0, 3} }
  local ann = troupe.actor{ name = "ann", at = {0, 0, 0} }
  local bob = troupe.actor{ name = "bob", at = {5, 0, 0} }
  local wa = ann:walk{ to = {0, 0, 6}, patience = 3 }
  local wb = bob:walk{ to = {5, 0, 6}, patience = 6 }
  -- Getting on is 0.05 s of the plan at 1.3 m/s: 6.5 cm nearer along the corridor.
  local left, ta, tb, last_move, best = nil, nil, nil, 0.0, 0.0
  run_until(function()
    if not left and troupe.time() >= 5 then left = leaver:walk{ to = {5, 0, 9.5} } end
    local _, z = flat(ann:position())
    if not ta and z > best + 0.065 then last_move, best = troupe.time(), z end
    if wa.status ~= "active" and not ta then ta = troupe.time() end
    if wb.status ~= "active" and not tb then tb = troupe.time() end
    return ta and tb
  end, 40)
  print(string.format("patience: ann %s at %.2f s (last moved on at %.2f s): %s; bob %s at %.2f s",
    wa.status, ta or -1, last_move, tostring(wa.error), wb.status, tb or -1))
  expect(wa.status == "failed", "ann gave up: " .. wa.status)
  expect(tostring(wa.error):find("^waited 3 s %(its `patience`%) getting no nearer its goal, 3%.%d%d m from it: `blocker` in its way") ~= nil,
         "the reason names the one in the way: " .. tostring(wa.error))
  -- She gave up about 3 s after she last got on (the plan's clock, which the walk
  -- measures, runs a few centimetres ahead of a body creeping up behind someone).
  expect(ta >= last_move + 2.5 and ta <= last_move + 3.5,
         string.format("gave up at %.2f s, last moved on at %.2f s", ta, last_move))
  expect(wb.status == "completed", "bob went on once the way was clear: " .. wb.status .. " " .. tostring(wb.error))
  expect(tb > 5, "bob arrived after the leaver left")
end)

test("a walk that gives up in mid-stride stops, its feet side by side, before it fails", function()
  -- It failed at once, a foot 6 cm up in the air for good.
  troupe.wall{ from = {-0.6, -1}, to = {-0.6, 8} }
  troupe.wall{ from = {0.6, -1}, to = {0.6, 8} }
  troupe.actor{ name = "blocker", at = {0, 0, 3} }
  local ann = troupe.actor{ name = "ann", at = {0, 0, 0} }
  local w = ann:walk{ to = {0, 0, 6}, patience = 0.3 }
  expect(run_until(function() return w.status ~= "active" end, 30), "ended")
  expect(w.status == "failed" and tostring(w.error):find("`blocker` in its way", 1, true) ~= nil,
         w.status .. " " .. tostring(w.error))
  local function feet()
    local l, r = ann:joint_position("l_ankle"), ann:joint_position("r_ankle")
    return l, r, math.sqrt((l[1] - r[1]) ^ 2 + (l[3] - r[3]) ^ 2)
  end
  local l, r, apart = feet()
  print(string.format("gave up at %.2f s: ankles %.3f and %.3f m up, %.3f m apart", troupe.time(), l[2], r[2], apart))
  expect(math.abs(l[2] - r[2]) < 0.005, string.format("both feet down: ankles %.3f and %.3f m up", l[2], r[2]))
  expect(apart < 0.45, string.format("side by side: %.3f m apart", apart))
  run(2)
  local l2, r2 = feet()
  expect(math.abs(l2[2] - l[2]) + math.abs(r2[2] - r[2]) < 1e-9, "and stays so")
end)

test("a walk with patience that goes the long way round a table is getting on, and keeps it", function()
  -- Its goal just behind a long table: for the first 3 s or so the walk goes further
  -- from it, but on along its route.
  local ann = troupe.actor{ name = "ann" }
  troupe.object{ name = "table", shape = "box", size = {6, 0.75, 0.6}, at = {0, 0.375, 1.2}, mass = 30 }
  local w = ann:walk{ to = {0, 0, 2.2}, patience = 1 }
  local farthest = 0.0
  expect(run_until(function()
    local p = ann:position()
    farthest = math.max(farthest, math.sqrt(p[1] ^ 2 + (p[3] - 2.2) ^ 2))
    return w.status ~= "active"
  end, 30), "ended")
  expect(farthest > 3, string.format("went away from the goal: at most %.2f m from it", farthest))
  expect(w.status == "completed", w.status .. " " .. tostring(w.error))
end)

test("troupe.deepest_overlap measures the two most overlapping body discs", function()
  troupe.actor{ name = "ann" }
  troupe.actor{ name = "bob", at = {3, 0, 0} }
  local d, a, b = troupe.deepest_overlap{ discs = true }
  expect(d == 0 and a == nil and b == nil, "no overlap yet: " .. d)
  troupe.actor{ name = "cid", at = {0.3, 0, 0} }
  d, a, b = troupe.deepest_overlap{ discs = true }
  expect(math.abs(d - (2 * RADIUS - 0.3)) < 0.005 and a == "ann" and b == "cid",
    string.format("%.3f between %s and %s", d, tostring(a), tostring(b)))
end)

test("walkers crossing a small plaza turn their bodies no faster than 6 rad/s and keep their pelvis up", function()
  -- The plaza of docs/images/plaza.png (four streams of 12). A new route round people
  -- standing that set off nearly behind a walker flipped its turn to the other side
  -- between two ticks (up to 161 rad/s here), and a push along a route just set off ran
  -- its clock, and the heading turning in with it, ahead by several ticks (37 rad/s).
  -- A walker whose body went on from a planted foot (one that had chosen to stay down,
  -- or the steering's landing 0.9 m from a body held back) lowered its pelvis
  -- until the leg reached: to 0.55 m here, to 0.10 m (on the floor) in the big plaza.
  local plaza = require("support.plaza_streams")
  local walkers = plaza.build{ planter = 2.5, planter_size = {1.2, 0.7, 1.2}, per_stream = 12,
                               columns = 4, back = 6, spread = 1.0 }
  local last = {}
  for i, w in ipairs(walkers) do
    w.actor:walk{ to = { w.gx, 0, w.gz }, speed = 1.3 }
    last[i] = w.actor:dof("root_yaw")
  end
  local dt = 1 / troupe.rate()
  local fastest, who, when = 0.0, "nobody", 0.0
  local lowest, low_who, low_when = math.huge, "nobody", 0.0
  run_until(function()
    for i, w in ipairs(walkers) do
      local y = w.actor:position()[2]
      if y < lowest then lowest, low_who, low_when = y, w.actor.name, troupe.time() end
      local yaw = w.actor:dof("root_yaw")
      local rate = math.abs(yaw - last[i]) / dt
      if rate > fastest then fastest, who, when = rate, w.actor.name, troupe.time() end
      last[i] = yaw
    end
    return false
  end, 20)
  print(string.format("small plaza: fastest body turn %.2f rad/s (%s at %.2f s)", fastest, who, when))
  expect(fastest <= 6 + 1e-6, string.format("%s turned at %.1f rad/s at %.2f s", who, fastest, when))
  -- Standing, the pelvis is 0.96 m up; the walk lowers it by at most 0.2 thigh heights.
  print(string.format("small plaza: lowest pelvis %.3f m (%s at %.2f s)", lowest, low_who, low_when))
  expect(lowest >= 0.72, string.format("%s's pelvis sank to %.3f m at %.2f s", low_who, lowest, low_when))
end)
