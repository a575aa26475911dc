-- Grasp, give and receive bend round other bodies (docs/navigation.md, "Solids"): the
-- arm motions of a grasp and of a hand-over take temporary goals round another actor's
-- hand or arm in their way (thesis 4.6.3), as a reach does; `detour = false` turns it
-- off. The deepest interpenetration of solids is what troupe.deepest_overlap() measures.

local LIMIT = 0.01
local solids = require("support.solids")
local watch, ended = solids.watch, solids.ended

-- Bob, on Ann's right, holds his left hand out across the way of her right hand from
-- her side to a cup in front of her.
local function hand_in_the_way()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {-0.75, 0, 0.3}, facing = 90 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
    at = {-0.2, 1.05, 0.4}, obstacle = false }
  local held = bob:reach{ hand = "left", target = {-0.25, 0.92, 0.18}, duration = 1 }
  held:wait()
  expect(held.status == "completed", "bob holds his hand out: " .. tostring(held.error))
  expect(troupe.deepest_overlap() == 0, "nothing touches before the grasp")
  return ann, cup
end

local function grasp_past_a_hand(detour)
  local ann, cup = hand_in_the_way()
  local g = ann:grasp{ object = cup, hand = "right", duration = 1.5, detour = detour }
  local ok, deepest, between = watch(function() return ended(g) end, 6)
  print(string.format("grasp past a hand (detour = %s): deepest %.4f m (%s), %d temporary goal(s)",
    tostring(detour), deepest, between, g.detours))
  expect(ok and g.status == "completed", "the grasp completed: " .. tostring(g.error))
  expect(cup.holder == ann, "ann holds the cup")
  return deepest, between, g.detours
end

test("a grasp bends round another actor's hand to a cup", function()
  local deepest, between, detours = grasp_past_a_hand(true)
  expect(detours >= 1, "a temporary goal was inserted")
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
end)

test("without detours the same grasp passes through the hand", function()
  local deepest, _, detours = grasp_past_a_hand(false)
  expect(detours == 0, "no temporary goal")
  expect(deepest > 0.02, string.format("only %.3f m: the straight motion should cross the hand", deepest))
end)

-- Ann gives Bob a cup while Cid, beside them, holds his right hand out between them,
-- across the way of Bob's receiving hand.
local function hand_over_beside_cid(detour)
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
    at = {-0.2, 1.05, 0.38} }
  local g = ann:grasp{ object = cup, hand = "right" }
  expect(run_until(function() return ended(g) end, 4) and g.status == "completed",
    "ann picks the cup up: " .. tostring(g.error))
  local cid = troupe.actor{ name = "cid", at = {0.7, 0, 0.55}, facing = 270 }
  local out = cid:reach{ hand = "right", target = {0.1, 0.95, 0.66}, duration = 1 }
  out:wait()
  expect(out.status == "completed", "cid holds his hand out: " .. tostring(out.error))
  expect(troupe.deepest_overlap() == 0, "nothing touches before the hand-over")
  local give = ann:give{ object = cup, to = bob, detour = detour }
  local receive = assert(bob:actions()[1], "bob got a receive action")
  expect(receive.kind == "receive", "bob's action is a receive: " .. receive.kind)
  local ok, deepest, between = watch(function() return ended(give) and ended(receive) end, 8)
  print(string.format("hand-over beside cid (detour = %s): deepest %.4f m (%s), give %d and receive %d temporary goal(s)",
    tostring(detour), deepest, between, give.detours, receive.detours))
  expect(ok and give.status == "completed" and receive.status == "completed",
    "give " .. give.status .. " " .. tostring(give.error) .. ", receive " .. receive.status .. " " .. tostring(receive.error))
  expect(cup.holder == bob and #ann:holding() == 0, "the cup changed hands")
  return deepest, between, give.detours + receive.detours
end

test("a hand-over bends round a third actor's hand and completes", function()
  local deepest, between, detours = hand_over_beside_cid(true)
  expect(detours >= 1, "a temporary goal was inserted")
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
end)

test("without detours the receiving arm passes through the third actor's hand", function()
  local deepest, _, detours = hand_over_beside_cid(false)
  expect(detours == 0, "no temporary goal")
  expect(deepest > 0.03, string.format("only %.3f m: the straight motion should cross the hand", deepest))
end)

test("a hand-over with nobody in the way takes no temporary goal and keeps the hands apart", function()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
  troupe.actor{ name = "cid", at = {-0.45, 0, 0.45}, facing = 90 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
    at = {-0.2, 1.05, 0.38} }
  local g = ann:grasp{ object = cup, hand = "right" }
  expect(run_until(function() return ended(g) end, 4) and g.status == "completed", tostring(g.error))
  local give = ann:give{ object = cup, to = bob }
  local receive = assert(bob:actions()[1], "bob got a receive action")
  local ok, deepest, between = watch(function() return ended(give) and ended(receive) end, 8)
  expect(ok and cup.holder == bob, "the cup changed hands: " .. tostring(give.error) .. " / " .. tostring(receive.error))
  expect(give.detours == 0 and receive.detours == 0, "nothing in the way")
  expect(deepest <= LIMIT, string.format("%.3f m between %s", deepest, between))
end)

test("detour must be a boolean", function()
  local ann = troupe.actor{ name = "ann" }
  troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1, at = {-0.2, 1.05, 0.38} }
  ---@diagnostic disable-next-line: assign-type-mismatch
  local ok, e = pcall(function() return ann:grasp{ object = "cup", detour = "no" } end)
  expect(not ok and tostring(e):find("detour") ~= nil, "a bad detour names the option: " .. tostring(e))
end)

-- A grasp going round another's arm held across the front (as in collision.lua's reach
-- over an arm): no DOF of the arm turns faster than 8 rad/s while its path runs, as a
-- reach's (its elbow turned at 14.6 rad/s in one tick before).
test("a grasp round another's arm turns no joint faster than 8 rad/s", function()
  local ann, _, cup = solids.arm_across(0.4, {0.2, 1.3, 0.3}, {-0.25, 1.65, 0.4})
  local g = ann:grasp{ object = cup, hand = "right", duration = 1.5 }
  local fastest, where = solids.fastest_dof(ann, "right_arm", g)
  print(string.format("grasp round an arm: fastest joint %.2f rad/s (%s), %d temporary goal(s)",
    fastest, where, g.detours))
  expect(g.status == "completed", "the grasp completed: " .. tostring(g.error))
  expect(g.detours >= 1, "it went round the arm")
  expect(fastest <= 8 + 1e-6, string.format("%s turned at %.2f rad/s", where, fastest))
end)
