-- Bodies never pass through each other (docs/navigation.md, "Solids"): the deepest
-- interpenetration of two actors' solids, or of an actor's solid and an obstacle, as
-- troupe.deepest_overlap() measures it; a reaching arm bends round another body; two
-- walkers in a corridor turn their shoulders.

-- The goal, in every scene: at most 1 cm.
local LIMIT = 0.01

-- Watching the deepest solid interpenetration while something runs (shared with
-- collision_hands.lua).
local solids = require("support.solids")
local watch = solids.watch

-- How far (degrees) the line of `a`'s shoulders is turned from the line of its hips,
-- seen from above.
local function shoulder_turn(a)
  local function yaw(l, r)
    local pl, pr = a:joint_position(l), a:joint_position(r)
    return math.atan(pl[3] - pr[3], pl[1] - pr[1])
  end
  local d = math.deg(yaw("l_shoulder", "r_shoulder") - yaw("l_hip", "r_hip"))
  return (d + 180) % 360 - 180
end

local function all_ended(walks)
  return function()
    for _, w in ipairs(walks) do
      if w.status ~= "completed" and w.status ~= "failed" then return false end
    end
    return true
  end
end

test("troupe.deepest_overlap measures solids and names them", function()
  troupe.actor{ name = "ann" }
  troupe.actor{ name = "bob", at = {2, 0, 0} }
  local d, a, b = troupe.deepest_overlap()
  expect(d == 0 and a == nil and b == nil, "nothing touches yet: " .. d)
  troupe.actor{ name = "cid", at = {0, 0, 0.25} }
  local sa, sb
  d, a, b, sa, sb = troupe.deepest_overlap()
  expect(d > 0.02 and a == "ann" and b == "cid", string.format("%.3f between %s and %s", d, tostring(a), tostring(b)))
  expect(type(sa) == "string" and type(sb) == "string", "the solids are named: " .. tostring(sa) .. ", " .. tostring(sb))
  troupe.wall{ from = {1.9, -1}, to = {1.9, 1}, thickness = 0.1 }
  troupe.object{ name = "crate", shape = "box", size = {0.4, 0.4, 0.4}, at = {-0.3, 0.2, 0} }
  -- The crate is an obstacle; ann's leg stands in it by more than cid overlaps her.
  d, a, b, sa, sb = troupe.deepest_overlap()
  expect(b == "crate" or b == "wall 1" or b == "cid", "an obstacle is named: " .. tostring(b))
  expect(sb == nil or b == "cid", "an obstacle has no solid name")
end)

test("a table between an actor and its goal: no solid enters it", function()
  local ann = troupe.actor{ name = "ann" }
  troupe.object{ name = "table", shape = "box", size = {2, 0.75, 1}, at = {0, 0.375, 2}, mass = 30 }
  local w = ann:walk{ to = {0, 0, 4} }
  local ok, deepest, between = watch(function() return w.status == "completed" end, 20)
  print(string.format("table: deepest solid interpenetration %.4f m (%s)", deepest, between))
  expect(ok, "completed: " .. tostring(w.error))
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
end)

-- The farthest (m, on the floor) either ankle of `a` is from its root: a leg reaches
-- about 0.85 m for an adult.
local function widest_stance(a)
  local r = a:position()
  local far = 0
  for _, side in ipairs({ "l", "r" }) do
    local p = a:joint_position(side .. "_ankle")
    far = math.max(far, math.sqrt((p[1] - r[1])^2 + (p[3] - r[3])^2))
  end
  return far
end

-- A followed path (a keyframed Global_motion) avoids no one: it goes where it was told.
-- Its body used to go on through whoever stood on its way, its feet left stepping in
-- place behind it (a leg 1.5 m from its root, 7.6 cm of a foot in another's leg, in the
-- crossing example). Now it is held at the other's body, its clock waiting, and slides
-- past where the way is open.
test("a followed path through someone standing is held at their body, its feet under it", function()
  local ann = troupe.actor{ name = "ann" }
  troupe.actor{ name = "bob", at = {0.15, 0, 2}, facing = 180 }
  local path = troupe.sequence{ root_x = { {0, 0}, {4, 0} }, root_z = { {0, 0}, {4, 4} } }
  local w = ann:walk{ follow = path }
  local widest = 0
  local ok, deepest, between = watch(function()
    widest = math.max(widest, widest_stance(ann))
    return w.status ~= "active"
  end, 20)
  local p = ann:position()
  print(string.format("followed path past someone standing: %s at t = %.2f s at (%.2f, %.2f); deepest %.4f m (%s); feet at most %.2f m from the root",
    w.status, troupe.time(), p[1], p[3], deepest, between, widest))
  expect(ok and w.status == "completed", "the walk ended: " .. w.status .. " " .. tostring(w.error))
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
  expect(widest < 0.7, string.format("a foot %.2f m from the root", widest))
  expect(p[3] > 3.5, string.format("went on to the path's end (z %.2f)", p[3]))
end)

-- A velocity walk goes straight ahead: at a wall it stops, and once it has stood there
-- for 10 s it fails, saying where and what holds it.
test("a velocity walk or a followed path into a wall stops at it and fails, naming the wall", function()
  local ann = troupe.actor{ name = "ann" }
  troupe.wall{ from = {-2, 2}, to = {2, 2}, thickness = 0.2, height = 2 }
  local w = ann:walk{ velocity = 1.2 }
  local ok, deepest, between = watch(function() return w.status ~= "active" end, 20)
  print(string.format("velocity walk into a wall: %s at t = %.2f s (%s); deepest %.4f m (%s); root at z %.2f",
    w.status, troupe.time(), tostring(w.error), deepest, between, ann:position()[3]))
  expect(ok and w.status == "failed", "the walk ended: " .. w.status)
  expect(tostring(w.error):find("stuck for 10 s, held by wall", 1, true), tostring(w.error))
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
  expect(ann:position()[3] < 1.8, string.format("stopped before the wall: z %.2f", ann:position()[3]))
  -- A followed path into a wall says how far from its end it stopped.
  troupe.wall{ from = {8, 2}, to = {12, 2}, thickness = 0.2, height = 2 }
  local bob = troupe.actor{ name = "bob", at = {10, 0, 0} }
  local f = bob:walk{ follow = troupe.sequence{ root_x = { {0, 0}, {4, 0} }, root_z = { {0, 0}, {4, 4} } } }
  local ok2, deepest2 = watch(function() return f.status ~= "active" end, 20)
  print(string.format("followed path into a wall: %s (%s); deepest %.4f m", f.status, tostring(f.error), deepest2))
  expect(ok2 and f.status == "failed", "the followed walk ended: " .. f.status)
  expect(tostring(f.error):find("^stuck 2%.%d%d m from its path's end for 10 s, held by wall 2"), tostring(f.error))
  expect(deepest2 <= LIMIT, string.format("%.3f m", deepest2))
end)

test("eight actors on a circle swap: no two solids interpenetrate", function()
  local actors, walks = {}, {}
  for i = 1, 8 do
    local a = (i - 1) * math.pi / 4
    local x, z = 3 * math.sin(a), 3 * math.cos(a)
    actors[i] = troupe.actor{ name = "a" .. i, at = {x, 0, z}, facing = math.deg(a) + 180 }
    walks[i] = actors[i]:walk{ to = { -x, 0, -z }, speed = 1.2 }
  end
  local ok, deepest, between = watch(all_ended(walks), 40)
  print(string.format("circle: deepest solid interpenetration %.4f m (%s)", deepest, between))
  expect(ok, "every walk ended")
  for i, w in ipairs(walks) do
    expect(w.status == "completed", actors[i].name .. ": " .. tostring(w.error))
  end
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
end)

test("two walkers pass in a 1.2 m corridor turning their shoulders, their solids apart", function()
  local ann, bob, walks = require("support.corridor")()
  local turned = { 0, 0 }
  local ended = all_ended(walks)
  local ok, deepest, between = watch(function()
    for i, a in ipairs({ ann, bob }) do turned[i] = math.max(turned[i], math.abs(shoulder_turn(a))) end
    return ended()
  end, 40)
  print(string.format("corridor: deepest solid interpenetration %.4f m (%s); shoulders turned %.0f° and %.0f°",
    deepest, between, turned[1], turned[2]))
  expect(ok and walks[1].status == "completed" and walks[2].status == "completed",
    "both arrived: " .. tostring(walks[1].error) .. " / " .. tostring(walks[2].error))
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
  -- The walk turns the shoulders by vt12's and vt6's torsion, 10° each at a person's
  -- range (runtime/body/src/template.rs, TRUNK), with the pelvis's own turn beside it.
  expect(turned[1] > 15 and turned[2] > 15, string.format("the shoulders turned to pass: %.0f° and %.0f°", turned[1], turned[2]))
end)

-- Ann squeezes between a wall and Bob standing: her chest turns towards him, and the walk
-- bends her elbows. A forearm bent from the turned chest pointed at him, her wrist 2–3 cm
-- further out than at rest (0.247–0.259 m from her root against 0.228 m; in the plaza a
-- walker's hand went 2 cm into a standing one's so); each upper arm is twisted back by
-- the turn, so the forearms keep along the way.
test("a walker squeezing past a standing actor turns its shoulders and keeps its hands in", function()
  troupe.wall{ from = {-0.69, -3}, to = {-0.69, 5}, thickness = 0.1 }
  local bob = troupe.actor{ name = "bob", at = {0.3, 0, 1} }
  local ann = troupe.actor{ name = "ann", at = {-0.24, 0, -2} }
  local function out() return ann:joint_position("l_wrist")[1] - ann:position()[1] end
  local rest = out()
  local w = ann:walk{ to = {-0.24, 0, 4} }
  local turn, widest = 0, 0
  local ok, deepest, between = watch(function()
    local z = ann:position()[3]
    if z > 0 and z < 2 then
      turn = math.max(turn, ann:dof("vt12_torsion") + ann:dof("vt6_torsion"))
      widest = math.max(widest, out())
    end
    return w.status == "completed"
  end, 20)
  print(string.format("squeezing past: chest turned %.0f°, left wrist %.3f m out (%.3f m at rest), deepest %.4f m (%s)",
    math.deg(turn), widest, rest, deepest, between))
  expect(ok and w.status == "completed", "arrived: " .. tostring(w.error))
  expect(turn > 0.2, string.format("the chest turned towards bob: %.2f rad", turn))
  expect(widest < rest + 0.01, string.format("the wrist %.3f m out, %.3f m at rest", widest, rest))
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
end)

test("a walker alone keeps its shoulders square", function()
  local ann = troupe.actor{ name = "ann" }
  local w = ann:walk{ to = {0, 0, 6} }
  local turned = 0
  run_until(function()
    turned = math.max(turned, math.abs(shoulder_turn(ann)))
    return w.status == "completed"
  end, 20)
  expect(w.status == "completed", "arrived: " .. tostring(w.error))
  expect(turned < 12, string.format("only the gait's counter-rotation: %.1f°", turned))
end)

-- Bob holds his left arm straight out across the way; a cup hangs above it, within
-- Ann's reach: her hand's straight path from her side to the cup crosses his arm.
local function arm_across()
  return solids.arm_across(0.5, {-0.12, 1.45, 0.3}, {-0.3, 1.78, 0.42})
end

test("a reaching arm bends round another actor's arm to a cup", function()
  local ann, _, cup = arm_across()
  local before = troupe.deepest_overlap()
  expect(before == 0, string.format("nothing touches before the reach: %.3f", before))
  local r = ann:reach{ hand = "right", target = cup, duration = 1.5 }
  local ok, deepest, between = watch(function() return solids.ended(r) end, 5)
  print(string.format("reach round an arm: deepest %.4f m (%s), %d temporary goal(s)", deepest, between, r.detours))
  expect(ok and r.status == "completed", "the reach completed: " .. tostring(r.error))
  expect(r.detours >= 1, "a temporary goal was inserted")
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
end)

-- Bob's arm reaches right across in front of Ann's chest, below her shoulder; the cup
-- is above it. Her hand must come up behind his arm and go over it, and her elbow and
-- forearm with it: a temporary goal that only cleared the hand put it in front of his
-- arm, and her upper arm crossed his (73 mm).
test("a hand going over another's arm takes its forearm over too", function()
  local ann, _, cup = solids.arm_across(0.4, {0.2, 1.3, 0.3}, {-0.25, 1.65, 0.4})
  local r = ann:reach{ hand = "right", target = cup, duration = 1.5 }
  local ok, deepest, between = watch(function() return solids.ended(r) end, 5)
  print(string.format("reach over an arm: deepest %.4f m (%s), %d temporary goal(s)", deepest, between, r.detours))
  expect(ok and r.status == "completed", "the reach completed: " .. tostring(r.error))
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
end)

-- In that sort of reach the shoulder girdle reaches its limit on the way and the IK
-- turns the arm another way at once: the shoulder's abduction jumped 31° in one tick
-- (10 ms). While the path runs no DOF of the arm turns faster than 8 rad/s.
test("a reach round another's arm turns no joint faster than 8 rad/s", function()
  local ann, _, cup = solids.arm_across(0.4, {0.0, 1.4, 0.3}, {-0.25, 1.75, 0.4})
  local r = ann:reach{ hand = "right", target = cup, duration = 1.5 }
  local fastest, where = solids.fastest_dof(ann, "right_arm", r)
  print(string.format("reach round an arm: fastest joint %.2f rad/s (%s)", fastest, where))
  expect(r.status == "completed", "the reach completed: " .. tostring(r.error))
  expect(fastest <= 8 + 1e-6, string.format("%s turned at %.2f rad/s", where, fastest))
end)

test("without detours the same reach passes through the arm", function()
  local ann, _, cup = arm_across()
  local r = ann:reach{ hand = "right", target = cup, duration = 1.5, detour = false }
  local ok, deepest, between = watch(function() return solids.ended(r) end, 5)
  print(string.format("reach through an arm: deepest %.4f m (%s)", deepest, between))
  expect(ok and r.status == "completed", "the reach completed: " .. tostring(r.error))
  expect(r.detours == 0, "no temporary goal")
  expect(deepest > 0.03, string.format("only %.3f m: the straight path should cross the arm", deepest))
end)
