-- Grasping, manipulation and interaction by hands (thesis 4.2–4.5).

local function dist(a, b)
  return math.sqrt((a[1] - b[1])^2 + (a[2] - b[2])^2 + (a[3] - b[3])^2)
end

local function done(a) return a.status == "completed" end

local solids = require("support.solids")

test("plan_grasp returns the table's type, the hands and frames", function()
  local ann = troupe.actor{ name = "ann" }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                             at = {-0.2, 1.05, 0.38} }
  local plan, why = troupe.plan_grasp(ann, cup)
  expect(plan ~= nil, tostring(why))
  expect(plan.type == "wrap" and plan.decided == "wrap", "a cup is wrapped: " .. plan.type)
  expect(#plan.hands == 1 and plan.hands[1].hand == "right", "with the right hand")
  expect(#plan.hands[1].palm == 3 and #plan.hands[1].rotation == 3, "palm and rotation")
  local pinch = troupe.plan_grasp(ann, "cup", { pattern = "pinch", hand = "right" })
  expect(pinch.type == "pinch" and pinch.decided == "wrap", "the pattern overrides the table")
  local far = troupe.object{ name = "far", shape = "sphere", radius = 0.04, at = {0, 1, 3} }
  local none, reason = troupe.plan_grasp(ann, far)
  expect(none == nil and reason:find("out of reach") ~= nil, tostring(reason))
end)

test("grasp a cup, it follows the hand, then place it", function()
  local ann = troupe.actor{ name = "ann" }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                             at = {-0.2, 1.05, 0.38} }
  local g = ann:grasp{ object = cup, hand = "right", duration = 0.8 }
  expect(run_until(function() return done(g) end, 4), "grasp completed: " .. tostring(g.error))
  expect(cup.holder == ann, "ann holds the cup")
  local held = ann:holding()
  expect(#held == 1 and held[1].name == "cup", "holding() lists it")
  local m = ann:manipulate{ object = cup, keys = { { t = 0.5, at = {-0.2, 1.15, 0.38} },
                                                   { t = 1.0, at = {-0.15, 1.15, 0.33} } } }
  expect(run_until(function() return done(m) end, 3), "manipulate completed: " .. tostring(m.error))
  expect(dist(cup:position(), {-0.15, 1.15, 0.33}) < 0.01, "the cup went along the keys")
  local p = ann:place{ object = cup, at = {-0.2, 1.05, 0.4}, duration = 0.8 }
  expect(run_until(function() return done(p) end, 3), "place completed: " .. tostring(p.error))
  expect(cup.holder == nil and #ann:holding() == 0, "let go")
  expect(dist(cup:position(), {-0.2, 1.05, 0.4}) < 0.01, "put down where asked")
end)

test("a hand that holds something grasps nothing else; auto takes the free hand", function()
  local ann = troupe.actor{ name = "ann" }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                             at = {-0.2, 1.0, 0.38} }
  local ball = troupe.object{ name = "ball", shape = "sphere", radius = 0.04, at = {-0.3, 1.0, 0.4} }
  local pen = troupe.object{ name = "pen", shape = "cylinder", radius = 0.01, height = 0.14,
                             at = {0.2, 1.0, 0.4} }
  expect(ann:grasp{ object = cup, hand = "right" }:wait() == "completed", "the cup in the right hand")
  local cup_at = cup:position()
  local same = ann:grasp{ object = ball, hand = "right" }
  expect(same:wait() == "failed" and same.error == "the right hand already holds `cup`: place or release it first",
         tostring(same.error))
  expect(dist(cup:position(), cup_at) < 1e-9 and ball.holder == nil, "nothing moved, nothing taken")
  local auto = ann:grasp{ object = ball }   -- nearer the right hand, which is full
  expect(auto:wait() == "completed" and ball.holder == ann, "auto took the left hand: " .. tostring(auto.error))
  expect(dist(ball:position(), ann:joint_position("l_wrist")) < 0.15, "the ball is in the left hand")
  local full = ann:grasp{ object = pen }
  expect(full:wait() == "failed" and full.error:find("both hands are full") ~= nil, tostring(full.error))
end)

test("a box held in both hands fills both: neither grasps anything else", function()
  local ann = troupe.actor{ name = "ann" }
  troupe.object{ name = "stand", shape = "box", size = {0.8, 0.75, 0.5}, at = {0, 0.375, 0.75}, mass = 20 }
  local box = troupe.object{ name = "box", shape = "box", size = {0.35, 0.25, 0.25}, at = {0, 0.875, 0.6},
                             mass = 2 }
  local pen = troupe.object{ name = "pen", shape = "cylinder", radius = 0.01, height = 0.14,
                             at = {0.3, 0.8, 0.6} }
  local g = ann:grasp{ object = box, hand = "both" }
  expect(g:wait() == "completed" and box.holder == ann, "the box in both hands: " .. tostring(g.error))
  for _, hand in ipairs({ "left", "right" }) do
    local other = ann:grasp{ object = pen, hand = hand }
    expect(other:wait() == "failed" and other.error == "the " .. hand .. " hand already holds `box`: place or release it first",
           hand .. ": " .. tostring(other.error))
  end
  local auto = ann:grasp{ object = pen }
  expect(auto:wait() == "failed" and auto.error:find("both hands are full") ~= nil, tostring(auto.error))
  expect(pen.holder == nil, "the pen is left")
  -- Letting go opens both hands (the one the box did not follow stayed closed).
  local closed = { ann:dof("l_index1_flexion"), ann:dof("r_index1_flexion") }
  local rel = ann:release{ object = box }
  expect(rel:wait() == "completed" and box.holder == nil, "released: " .. tostring(rel.error))
  expect(closed[1] > 0.05 and ann:dof("l_index1_flexion") < 0.5 * closed[1]
         and closed[2] > 0.05 and ann:dof("r_index1_flexion") < 0.5 * closed[2],
         string.format("both hands open: index %.2f → %.2f (left), %.2f → %.2f (right)", closed[1],
                       ann:dof("l_index1_flexion"), closed[2], ann:dof("r_index1_flexion")))
end)

test("a receive with its hands full fails when it starts, not when the giver arrives", function()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0.9, 0, 0} }
  troupe.object{ name = "stand", shape = "box", size = {0.8, 0.75, 0.5}, at = {0.9, 0.375, 0.75}, mass = 20 }
  local box = troupe.object{ name = "box", shape = "box", size = {0.35, 0.25, 0.25}, at = {0.9, 0.875, 0.6},
                             mass = 2 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1, at = {-0.2, 1.0, 0.38} }
  expect(bob:grasp{ object = box, hand = "both" }:wait() == "completed", "bob holds the box")
  expect(ann:grasp{ object = cup, hand = "right" }:wait() == "completed", "ann holds the cup")
  local t0 = troupe.time()
  local give = ann:give{ object = cup, to = bob }
  local rx = bob:receive{ object = cup, from = ann }
  expect(run_until(function() return rx.status ~= "active" and rx.status ~= "pending" end, 2), "ended")
  expect(rx.status == "failed" and rx.error:find("both hands are full (`box` and `box`)", 1, true) ~= nil,
         rx.status .. ": " .. tostring(rx.error))
  expect(troupe.time() - t0 < 0.05, string.format("at once: %.2f s", troupe.time() - t0))
  run_until(function() return give.status ~= "active" end, 2)
  expect(give.status == "failed", "the give fails with it: " .. give.status)
end)

test("every pattern takes small things with the palm within reach of them", function()
  -- A hand that closes more than 0.1 m from its object fails (PALM_REACH): fingertip
  -- grasps of small things must still pass.
  local ann = troupe.actor{ name = "ann" }
  local small = {
    troupe.object{ name = "pen", shape = "cylinder", radius = 0.006, height = 0.14, at = {-0.2, 1.0, 0.38} },
    troupe.object{ name = "coin", shape = "cylinder", radius = 0.012, height = 0.003, at = {-0.25, 1.0, 0.35} },
    troupe.object{ name = "marble", shape = "sphere", radius = 0.008, at = {-0.2, 1.05, 0.4} },
  }
  for _, thing in ipairs(small) do
    for _, pattern in ipairs({ "pinch", "tripod", "lateral" }) do
      local g = ann:grasp{ object = thing, hand = "right", pattern = pattern }
      expect(g:wait() == "completed", thing.name .. ", " .. pattern .. ": " .. tostring(g.error))
      expect(ann:release{ object = thing }:wait() == "completed", "released")
    end
  end
end)

test("a book, a phone and a tray lying flat on a table are taken with the hand out of the table", function()
  -- Taken by the edge nearest the hand, as a cup is, a flat thing's grasp put the
  -- fingers under it and the hand 2-6 cm into the table it lay on (the book 4.0 cm, the
  -- phone 5.5, the tray 2.4): a frame whose hand lies in the furniture round the object
  -- now backs off while it still touches the object, or is tried last.
  local things = {
    { name = "book", size = {0.18, 0.04, 0.25} },
    { name = "phone", size = {0.07, 0.01, 0.15} },
    { name = "tray", size = {0.4, 0.03, 0.3} },
  }
  for i, t in ipairs(things) do
    local x = (i - 2) * 3
    local ann = troupe.actor{ name = "ann_" .. t.name, at = {x, 0, -0.55} }
    troupe.object{ name = "table_" .. t.name, shape = "box", size = {0.8, 0.75, 0.6},
                   at = {x, 0.375, 0.1}, mass = 20 }
    local thing = troupe.object{ name = t.name, shape = "box", size = t.size,
                                 at = {x, 0.75 + t.size[2] / 2, -0.05}, mass = 0.5 }
    local g = ann:grasp{ object = thing }
    local lift ---@type Action?
    local ok, deepest, between = solids.watch(function()
      if not lift and g.status == "completed" then
        lift = ann:manipulate{ object = thing, keys = { { t = 0.6, at = {x, 1.0, -0.15} } } }
      end
      return lift ~= nil and solids.ended(lift)
    end, 10)
    expect(ok and lift ~= nil and lift.status == "completed", t.name .. ": grasp " .. g.status .. " " .. tostring(g.error))
    print(string.format("%s taken and lifted, the deepest solids %.4f m (%s)", t.name, deepest, between))
    expect(deepest <= 0.002, string.format("%s: %.3f m deep (%s)", t.name, deepest, between))
  end
end)

test("manipulate with a function of time", function()
  local ann = troupe.actor{ name = "ann" }
  local ball = troupe.object{ name = "ball", shape = "sphere", radius = 0.04, at = {-0.2, 1.05, 0.38} }
  local g = ann:grasp{ object = ball }
  expect(run_until(function() return done(g) end, 4), "grasp: " .. tostring(g.error))
  local m = ann:manipulate{ object = ball, duration = 1,
                            keys = function(t) return {-0.2, 1.05 + 0.1 * t, 0.38} end }
  expect(run_until(function() return done(m) end, 3), "manipulate: " .. tostring(m.error))
  expect(math.abs(ball:position()[2] - 1.15) < 0.01, "lifted 10 cm")
  -- 0.28 s is 7.000…01 sampling steps of 0.04 s: the last key must not repeat.
  local back = ann:manipulate{ object = ball, duration = 0.28,
                               keys = function(t) return {-0.2, 1.15 - 0.1 * t / 0.28, 0.38} end }
  expect(run_until(function() return done(back) end, 2), "manipulate 0.28 s: " .. tostring(back.error))
  expect(math.abs(ball:position()[2] - 1.05) < 0.01, "put back down")
end)

test("a grasp, place or manipulate whose scope has nothing of the arm is refused", function()
  -- They ran with every arm write refused: the grasp failed "the hand closed 0.35 m
  -- from `cup`", the manipulate completed with the cup where it was.
  local ann = troupe.actor{ name = "ann" }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                             at = {-0.2, 1.05, 0.38} }
  local function refused(f)
    local ok, e = pcall(f)
    expect(not ok, "refused")
    e = tostring(e)
    expect(e:find("option `scope` must hold a DOF that moves the", 1, true) ~= nil, e)
    expect(e:find("grasp.lua:", 1, true) ~= nil, "says where: " .. e)
  end
  refused(function() return ann:grasp{ object = cup, scope = "head" } end)
  local g = ann:grasp{ object = cup, hand = "right", scope = "right_arm+right_hand" }
  expect(run_until(function() return done(g) end, 4), "a scope with the arm grasps: " .. tostring(g.error))
  refused(function() return ann:manipulate{ object = cup, scope = "left_arm",
                                            keys = { { t = 0.5, at = {-0.2, 1.15, 0.38} } } } end)
  refused(function() return ann:place{ object = cup, at = {-0.2, 1.05, 0.4}, scope = "spine" } end)
  expect(#ann:actions() == 0, "nothing started")
end)

test("manipulate overhead turns no joint faster than 8 rad/s", function()
  -- The ball raised over the head: the shoulder's flexion locked at its limit and the IK
  -- found the arm another way in one tick (89.8 rad/s).
  local ann = troupe.actor{ name = "ann" }
  local ball = troupe.object{ name = "ball", shape = "sphere", radius = 0.04, at = {-0.2, 1.05, 0.38} }
  local g = ann:grasp{ object = ball, hand = "right" }
  expect(g:wait() == "completed", "grasp: " .. tostring(g.error))
  local m = ann:manipulate{ object = ball, keys = { { t = 1.0, at = {-0.2, 1.9, 0.2} } } }
  local fastest, where = solids.fastest_dof(ann, "right_arm", m)
  print(string.format("manipulate overhead: fastest DOF %.2f rad/s (%s)", fastest, where))
  expect(m.status == "completed", "manipulate: " .. tostring(m.error))
  expect(fastest <= 8 + 1e-6, string.format("%s turned at %.2f rad/s", where, fastest))
end)

test("give a cup: the receiver holds it and both complete", function()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                             at = {-0.2, 1.05, 0.38} }
  local g = ann:grasp{ object = cup, hand = "right" }
  expect(run_until(function() return done(g) end, 4), "grasp: " .. tostring(g.error))
  local give = ann:give{ object = cup, to = bob }
  local receive = bob:actions()[1]
  expect(receive ~= nil and receive.kind == "receive", "bob got a receive action")
  expect(run_until(function() return done(give) and done(receive) end, 8),
         "give " .. give.status .. " " .. tostring(give.error) .. ", receive " .. receive.status .. " " .. tostring(receive.error))
  expect(cup.holder == bob and #ann:holding() == 0, "bob holds the cup, ann does not")
end)

test("bad input fails with a reason", function()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0.6, 0, 0} }
  local ok0, e0 = pcall(function() return ann:grasp{ object = "nothing" } end)
  expect(not ok0 and e0:find("nothing") ~= nil, "an unknown name is a Lua error: " .. tostring(e0))
  local ok, e = pcall(function() return ann:grasp{ object = 42 } end)
  expect(not ok and tostring(e):find("must be an object") ~= nil, "a number is a script error: " .. tostring(e))
  local far = troupe.object{ name = "far", shape = "box", size = {0.06, 0.06, 0.06}, at = {0, 1, 3} }
  local g = ann:grasp{ object = far }
  expect(run_until(function() return g.status == "failed" end, 1), "out of reach fails")
  expect(g.error:find("out of reach") ~= nil, g.error)
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                             at = {0.4, 1.05, 0.38} }
  local b = bob:grasp{ object = cup, hand = "right" }
  expect(run_until(function() return done(b) end, 4), "bob grasps: " .. tostring(b.error))
  local a = ann:grasp{ object = cup }
  expect(run_until(function() return a.status == "failed" end, 1), "taking bob's cup fails")
  expect(a.error:find("held by `bob`") ~= nil, a.error)
  local r = ann:release{ object = cup }
  expect(run_until(function() return r.status == "failed" end, 1), "releasing what you do not hold fails")
  expect(r.error:find("does not hold") ~= nil, r.error)
  ok, e = pcall(function() return ann:grasp{ object = cup, hand = "middle" } end)
  expect(not ok and tostring(e):find("unknown hand") ~= nil, tostring(e))
  ok, e = pcall(function() return ann:grasp{ object = cup, pattern = "fist" } end)
  expect(not ok and tostring(e):find("unknown grasp pattern") ~= nil, tostring(e))
end)

-- Ann holds Bob's left hand in her right, 0.45 m apart, for 2 s: both actors, her hold
-- and his follow_hand.
local function holding_hands(apart)
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {-(apart or 0.45), 0, 0} }
  local h = ann:hold_hand{ other = bob, hand = "right", other_hand = "left" }
  local follow = bob:actions()[1]
  expect(follow.kind == "follow_hand", "bob follows")
  run(2.0)
  expect(h.status == "active", "holding: " .. h.status .. " " .. tostring(h.error))
  return ann, bob, h, follow
end

test("hold hands: the wrists stay within 1 cm while the active actor moves by keyframes", function()
  local ann, bob, h, follow = holding_hands()
  local function gap()
    local a, b = ann:joint_position("r_wrist"), bob:joint_position("l_wrist")
    return {a[1] - b[1], a[2] - b[2], a[3] - b[3]}
  end
  local g0 = gap()
  local x0 = ann:dof("root_x")
  local path = troupe.sequence{ root_x = { {0, x0}, {1, x0 + 0.06}, {2, x0} },
                                root_z = { {0, 0}, {1, 0.1}, {2, 0} } }
  local walk = ann:play(path)
  local worst = 0
  while walk.status ~= "completed" do
    run(0.05)
    worst = math.max(worst, dist(gap(), g0))
  end
  expect(worst < 0.01, "wrists kept within a centimetre: " .. worst)
  expect(h.status == "active" and follow.status == "active", "still holding")
  h:cancel()
  follow:cancel()
  -- Both let go, the active hand opening and its arm coming down (1.2 s).
  expect(run_until(function() return h.status == "cancelled" and follow.status == "cancelled" end, 2), "let go")
end)

test("a hold fails fast, saying why, when the follower is cancelled or walks away", function()
  -- Both stayed `active` for good, the hands 2.3 m apart.
  local _, _, h, follow = holding_hands()
  follow:cancel()
  expect(run_until(function() return h.status ~= "active" end, 0.1), "the hold ended")
  expect(h.status == "failed" and tostring(h.error):find("^`bob`'s follow_hand ended first %(cancelled") ~= nil,
         h.status .. ": " .. tostring(h.error))

  local carl = troupe.actor{ name = "carl", at = {5, 0, 0} }
  local dan = troupe.actor{ name = "dan", at = {4.55, 0, 0} }
  local h2 = carl:hold_hand{ other = dan, hand = "right", other_hand = "left" }
  local f2 = dan:actions()[1]
  run(2.0)
  expect(h2.status == "active", "holding: " .. tostring(h2.error))
  dan:walk{ to = {2, 0, 0} }
  expect(run_until(function() return h2.status ~= "active" end, 3), "the hold ended")
  expect(h2.status == "failed" and tostring(h2.error):find("^the hands came apart: `dan`'s left hand is [%d.]+ m from `carl`'s right hand$") ~= nil,
         h2.status .. ": " .. tostring(h2.error))
  -- The follower lets go at once and lowers its arm (0.8 s).
  expect(run_until(function() return f2.status ~= "active" end, 0.85), "the follower let go too: " .. f2.status)
end)

test("a hand following another's turns no joint faster than 8 rad/s", function()
  -- Ann steps towards Bob and back, holding his hand: his arm's IK turned its
  -- sternoclavicular joint at 16.4 rad/s in one tick.
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {-0.45, 0, 0} }
  local h = ann:hold_hand{ other = bob, hand = "right", other_hand = "left" }
  run(2.0)
  expect(h.status == "active", "holding: " .. tostring(h.error))
  local function gap()
    local a, b = ann:joint_position("r_wrist"), bob:joint_position("l_wrist")
    return {a[1] - b[1], a[2] - b[2], a[3] - b[3]}
  end
  local g0 = gap()
  local moves = ann:play(troupe.sequence{ root_x = { {0, 0}, {1, -0.3}, {2, 0} } })
  local fastest, where = solids.fastest_dof(bob, "left_arm", moves)
  print(string.format("following a hand: fastest DOF %.2f rad/s (%s), the wrists %.4f m off after",
    fastest, where, dist(gap(), g0)))
  expect(fastest <= 8 + 1e-6, string.format("%s turned at %.2f rad/s", where, fastest))
end)

test("two hands going for one cup: the first to reach for it takes it, the other gives up at once", function()
  local ann = troupe.actor{ name = "ann", at = {-0.35, 0, 0}, facing = 90 }
  local bob = troupe.actor{ name = "bob", at = {0.35, 0, 0}, facing = 270 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.10,
                             at = {0, 1.0, 0.15}, obstacle = false }
  -- At once: claims of one tick go in actor order, so ann (created first) has it.
  local a = ann:grasp{ object = cup, hand = "right" }
  local b = bob:grasp{ object = cup, hand = "left" }
  local deepest = 0
  expect(run_until(function()
    local d = troupe.deepest_overlap()
    if d and d > deepest then deepest = d end
    return done(a) and b.status == "failed"
  end, 4), "ann: " .. a.status .. ", bob: " .. b.status .. " " .. tostring(b.error))
  expect(b.error == "`ann` is already reaching for `cup`", tostring(b.error))
  expect(cup.holder == ann, "ann holds it")
  print(string.format("two hands for one cup: bob gave up; the hands met %.1f mm deep at most", 1000 * deepest))
  expect(deepest < 0.01, string.format("no hand inside the other: %.3f m", deepest))
  -- Later, while ann holds it, a plain grasp of it fails at once, saying how to take it.
  local c = bob:grasp{ object = cup, hand = "left" }
  expect(run_until(function() return c.status == "failed" end, 0.05), "refused: " .. c.status)
  expect(c.error:find("is held by `ann`", 1, true) ~= nil, tostring(c.error))
end)

test("an adult hands a cup to a child at the child's height, leaning to it", function()
  local ann = troupe.actor{ name = "ann", facing = 90 }
  local kid = troupe.actor{ name = "kid", template = "child", at = {0.8, 0, 0}, facing = 270 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.10,
                             at = {0.35, 1.0, 0.25}, obstacle = false }
  expect(ann:grasp{ object = cup, hand = "right" }:wait() == "completed", "grasped")
  local shoulder = kid:joint_position("r_shoulder")[2]
  local give = ann:give{ object = cup, to = kid }
  local receive = kid:actions()[#kid:actions()]
  local met, raised, leaned = nil, 0, 0
  expect(run_until(function()
    raised = math.max(raised, math.deg(kid:dof("r_shoulder_flexion")), math.deg(kid:dof("l_shoulder_flexion")))
    leaned = math.max(leaned, ann:dof("vl5_flexion"))
    if not met and cup.holder == kid then met = cup:position()[2] end
    return done(give) and done(receive)
  end, 8), "handed over: " .. give.status .. " " .. tostring(give.error))
  print(string.format("handed to a child: the cup taken %.2f m high, the child's shoulders at %.2f m, " ..
                      "its arm raised %.0f° at most; ann leaned %.0f° and stands straight again (%.0f°)",
                      met, shoulder, raised, math.deg(leaned), math.deg(math.abs(ann:dof("vl5_flexion")))))
  expect(cup.holder == kid and math.abs(met - 0.79 * shoulder) < 0.02,
         string.format("taken 21 %% of the way down from the child's shoulders: %.2f against %.2f m",
                       met, shoulder))
  expect(raised < 60, string.format("the child's arm raised %.0f°", raised))
  expect(leaned > math.rad(5) and math.abs(ann:dof("vl5_flexion")) < math.rad(1),
         string.format("the adult leaned (%.1f°) and straightened", math.deg(leaned)))
end)

test("a giver crouched from picking a cup off a low table stands up as it hands it over", function()
  local ann = troupe.actor{ name = "ann", facing = 0 }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
  troupe.object{ name = "table", shape = "box", size = {0.6, 0.75, 0.5}, at = {-0.8, 0.375, 0.45}, mass = 20 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.1,
                             at = {-0.65, 0.8, 0.35}, mass = 0.3 }
  expect(ann:grasp{ object = cup, hand = "left" }:wait() == "completed", "grasped")
  expect(ann:dof("root_y") < -0.2, "she crouched to pick it up: " .. ann:dof("root_y"))
  local shoulder = bob:joint_position("r_shoulder")[2]
  local standing = bob:joint_position("l_ankle")[2]
  local give = ann:give{ object = cup, to = bob }
  local met, lowest = nil, math.huge
  expect(run_until(function()
    if not met and cup.holder == bob then met = cup:position()[2] end
    lowest = math.min(lowest, ann:joint_position("l_ankle")[2], ann:joint_position("r_ankle")[2])
    return give.status == "completed" or give.status == "failed"
  end, 8), "the give ended: " .. give.status)
  -- Her legs straighten with her pelvis, the feet flat on the floor all the way up.
  expect(math.abs(lowest - standing) < 0.003,
         string.format("ankles at least %.3f m high (standing: %.3f)", lowest, standing))
  expect(give.status == "completed", "handed over: " .. tostring(give.error))
  -- Planned from her crouch, the cup met bob's hand at 0.69 m and he crouched to it.
  expect(math.abs(met - 0.79 * shoulder) < 0.03,
         string.format("taken 21 %% below the shoulders: %.3f against %.3f m", met, 0.79 * shoulder))
  expect(math.abs(ann:dof("root_y")) < 0.005 and math.abs(ann:dof("vl5_flexion")) < 0.01,
         string.format("ann stands upright: pelvis %.3f m, vl5 %.3f rad", ann:dof("root_y"), ann:dof("vl5_flexion")))
  -- Her empty arm has come down to her side, not left held out where she gave.
  expect(math.abs(ann:dof("l_shoulder_flexion")) < 0.01 and math.abs(ann:dof("l_elbow_flexion")) < 0.01,
         string.format("the arm hangs: shoulder %.2f, elbow %.2f rad", ann:dof("l_shoulder_flexion"), ann:dof("l_elbow_flexion")))
end)

test("a child hands a ball it picked up at its hip to an adult, 0.6 to 0.9 m away", function()
  -- The hand that took the ball from beside the hip (fingers down) cannot bring it up and
  -- forward at that angle: the ball turns about the vertical on its way instead.
  local gives = {}
  for i, d in ipairs({0.6, 0.7, 0.8, 0.9}) do
    local z = i * 3
    local kid = troupe.actor{ name = "kid" .. i, template = "child", at = {d, 0, z}, facing = -90 }
    local mum = troupe.actor{ name = "mum" .. i, height = 1.68, at = {0, 0, z}, facing = 90 }
    local ball = troupe.object{ name = "ball" .. i, shape = "sphere", radius = 0.06,
                                at = {d - 0.05, 0.6, z - 0.25}, mass = 0.2 }
    kid:behave(function(self)
      self:grasp{ object = ball, hand = "right" }:wait()
      gives[i] = self:give{ object = ball, to = mum }
      gives[i]:wait()
      expect(ball.holder == mum, string.format("%.1f m: mum holds the ball", d))
    end)
  end
  expect(run_until(function()
    for i = 1, 4 do
      if not gives[i] or gives[i].status == "active" or gives[i].status == "pending" then return false end
    end
    return true
  end, 12), "every give ended")
  for i = 1, 4 do
    expect(gives[i].status == "completed", string.format("give %d: %s (%s)", i, gives[i].status, tostring(gives[i].error)))
  end
end)

test("people of different heights shake hands, and a child holds an adult's hand walking", function()
  -- The taller one's arm does not reach as low as the shorter's shoulders ask: the hand
  -- is held out higher; a taller person cannot reach below its own hanging hand: the
  -- shorter lifts its hand to be taken.
  local shakes = {}
  for i, h in ipairs({ {1.65, 1.82}, {1.60, 1.70}, {1.80, 1.90}, {1.90, 1.65} }) do
    local a = troupe.actor{ name = "a" .. i, height = h[1], at = {-0.45, 0, i * 3}, facing = 90 }
    local b = troupe.actor{ name = "b" .. i, height = h[2], at = {0.45, 0, i * 3}, facing = -90 }
    shakes[i] = { a:shake_hands{ other = b }, h }
  end
  local mum = troupe.actor{ name = "mum", height = 1.7, at = {5, 0, 0} }
  local kid = troupe.actor{ name = "kid", template = "child", height = 1.15, at = {4.6, 0, 0} }
  local hold = mum:hold_hand{ other = kid, hand = "right", other_hand = "left" }
  run(2.5)
  expect(hold.status == "active", "mum holds kid's hand: " .. hold.status .. " " .. tostring(hold.error))
  local a = mum:walk{ path = { {5, 2}, {5, 4} }, speed = 0.8, arms = false }
  local b = kid:walk{ path = { {4.6, 2}, {4.6, 4} }, speed = 0.8, arms = false }
  expect(run_until(function() return a.status == "completed" and b.status == "completed" end, 10),
         "they walked: " .. a.status .. " " .. b.status)
  expect(hold.status == "active", "still hand in hand: " .. hold.status .. " " .. tostring(hold.error))
  for i, s in ipairs(shakes) do
    expect(s[1]:wait() == "completed", string.format("%.2f m shakes %.2f m: %s %s", s[2][1], s[2][2],
                                                     s[1].status, tostring(s[1].error)))
  end
end)

test("shake hands facing each other: bob holds his hand out as ann reaches for it; both complete", function()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
  local s = ann:shake_hands{ other = bob }
  local f = bob:actions()[#bob:actions()]
  -- Ann's arm turns no joint faster than 8 rad/s: as the hand began to open, the arm
  -- snapped from where the shake left it back to its planned posture (9.3 rad/s).
  local fastest, where = solids.fastest_dof(ann, "right_arm", s)
  print(string.format("shake hands: fastest DOF %.2f rad/s (%s)", fastest, where))
  expect(run_until(function() return done(s) and done(f) end, 6),
         "shake: " .. s.status .. " " .. tostring(s.error) .. ", follow: " .. f.status)
  expect(fastest <= 8 + 1e-6, string.format("%s turned at %.2f rad/s", where, fastest))
  -- Both let go and their arms came down to their sides (they stayed held out).
  for _, who in ipairs({ann, bob}) do
    expect(math.abs(who:dof("r_shoulder_flexion")) < 0.01 and math.abs(who:dof("r_elbow_flexion")) < 0.01,
           string.format("%s's arm hangs: shoulder %.2f, elbow %.2f rad", who.name,
                         who:dof("r_shoulder_flexion"), who:dof("r_elbow_flexion")))
  end
end)

test("shake hands at 0.5 to 1.1 m apart, the other's hand hanging: it is held out, both complete", function()
  for i, d in ipairs({ 0.5, 0.7, 0.9, 1.1 }) do
    local ann = troupe.actor{ name = "ann" .. i, at = {3 * i, 0, 0} }
    local bob = troupe.actor{ name = "bob" .. i, at = {3 * i, 0, d}, facing = 180 }
    local s = ann:shake_hands{ other = bob }
    local f = bob:actions()[#bob:actions()]
    local held_out = 0
    expect(run_until(function()
      -- Bob's wrist comes out towards ann before the hands close.
      held_out = math.max(held_out, -(bob:joint_position("r_wrist")[3] - d))
      return done(s) and done(f)
    end, 6), string.format("%.1f m: shake %s %s, follow %s", d, s.status, tostring(s.error), f.status))
    print(string.format("shake hands %.1f m apart: bob's wrist came %.2f m out towards ann", d, held_out))
    expect(held_out > 0.3 * d, string.format("%.1f m: held out %.2f m", d, held_out))
  end
  -- Too far apart to reach each other: fails at once, saying so.
  local ann = troupe.actor{ name = "far_ann", at = {20, 0, 0} }
  local bob = troupe.actor{ name = "far_bob", at = {20, 0, 2.5}, facing = 180 }
  local s = ann:shake_hands{ other = bob }
  expect(run_until(function() return s.status == "failed" end, 0.1), "failed: " .. s.status)
  expect(s.error:find("cannot hold out the right hand to `far_ann` 2.50 m away") ~= nil, s.error)
end)

test("a grasp that may not lean or crouch says so when the arm alone misses", function()
  -- A grasp started as a dying receive still held the spine tried the arm alone and said
  -- only "the best grasp misses by 0.336 m", where leaning would have reached.
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.1, at = {0.2, 0.8, 0.75}, mass = 0.3 }
  local ann = troupe.actor{ name = "ann" }
  local g = ann:grasp{ object = cup, scope = "right_arm+right_hand" }
  expect(run_until(function() return done(g) or g.status == "failed" end, 3), "ended: " .. g.status)
  expect(g.status == "failed" and tostring(g.error):find("(the arm alone: the spine and the legs are outside the action's scope", 1, true),
         tostring(g.error))
  local g2 = ann:grasp{ object = cup }
  expect(run_until(function() return done(g2) or g2.status == "failed" end, 6), "ended")
  expect(g2.status == "completed", "with the whole body it reaches: " .. tostring(g2.error))
end)

test("a hand that holds something shakes or holds no hand: refused at once, naming what it holds", function()
  -- A shake with a cup in the hand ran: the other's fingers closed round the cup.
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.1, at = {0.25, 1.05, 0.35}, mass = 0.3 }
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
  expect(ann:grasp{ object = cup, hand = "right" }:wait() == "completed", "ann holds the cup")
  local s = ann:shake_hands{ other = bob }
  expect(run_until(function() return s.status == "failed" end, 0.1), "failed at once: " .. s.status)
  expect(tostring(s.error):find("the right hand already holds `cup`: place or release it first", 1, true), tostring(s.error))
  -- The other's hand full: bob's shake with ann, who holds the cup in her right (once
  -- bob's arm is his again: the follower the first shake gave him lets go).
  local s2 = bob:shake_hands{ other = ann }
  expect(run_until(function() return s2.status == "failed" end, 3), "failed as it starts: " .. s2.status)
  expect(tostring(s2.error):find("`ann`'s right hand already holds `cup`", 1, true), tostring(s2.error))
  -- With her left hand, which holds nothing, the shake goes on.
  local s3 = ann:shake_hands{ other = bob, hand = "left", other_hand = "left" }
  expect(run_until(function() return s3.status ~= "pending" end, 3), "the left shake starts: " .. s3.status)
  expect(s3.status == "active", "the left shake runs: " .. s3.status .. " " .. tostring(s3.error))
  expect(cup.holder == ann, "she still holds the cup")
end)

test("walking hand in hand 0.6 m apart, bodies apart: they walk together, the hold holds", function()
  -- Their discs do not touch: until held hands made them companions, each avoided the
  -- other and the hold broke ("the hands came apart").
  local ann, bob, h = holding_hands(0.6)
  local a = ann:walk{ path = { {0, 2}, {1, 4}, {1, 6} }, speed = 1.0, arms = false }
  local b = bob:walk{ path = { {-0.6, 2}, {0.4, 4}, {0.4, 6} }, speed = 1.0, arms = false }
  local widest = 0
  expect(run_until(function()
    local p, q = ann:position(), bob:position()
    widest = math.max(widest, math.sqrt((p[1] - q[1])^2 + (p[3] - q[3])^2))
    return a.status ~= "active" and b.status ~= "active"
  end, 15), "the walks ended")
  expect(h.status == "active", "still holding: " .. h.status .. " " .. tostring(h.error))
  expect(widest < 0.65, string.format("they kept 0.6 m apart: at most %.2f m", widest))
  local p, q = ann:position(), bob:position()
  expect(math.abs(p[1] - 1) < 0.02 and math.abs(p[3] - 6) < 0.02 and math.abs(q[1] - 0.4) < 0.02 and math.abs(q[3] - 6) < 0.02,
         string.format("both arrived: ann (%.2f, %.2f), bob (%.2f, %.2f)", p[1], p[3], q[1], q[3]))
end)

test("walking hand in hand: the wrists stay within 1 cm, cancelling the hold frees the follower", function()
  local ann, bob, h, follow = holding_hands()
  local function gap()
    local a, b = ann:joint_position("r_wrist"), bob:joint_position("l_wrist")
    return {a[1] - b[1], a[2] - b[2], a[3] - b[3]}
  end
  local g0 = gap()
  local a = ann:walk{ path = { {0, 1.5}, {0.5, 3} }, speed = 1.0, arms = false }
  local b = bob:walk{ path = { {-0.45, 1.5}, {0.05, 3} }, speed = 1.0, arms = false }
  local worst = 0
  while a.status ~= "completed" do
    expect(a.status ~= "failed" and b.status ~= "failed", "walking: " .. tostring(a.error or b.error))
    run(0.05)
    -- The pair turns on the way, so the wrist-to-wrist vector turns too: its length
    -- is what the hold keeps.
    worst = math.max(worst, math.abs(dist(gap(), {0, 0, 0}) - dist(g0, {0, 0, 0})))
  end
  expect(ann:position()[3] > 2.9, "ann arrived: " .. ann:position()[3])
  expect(worst < 0.01, "wrists kept within a centimetre while walking: " .. worst)
  -- Cancelling the active side ends the passive side as well.
  h:cancel()
  expect(run_until(function() return h.status == "cancelled" and follow.status == "completed" end, 2.5),
         "let go: " .. h.status .. ", follow " .. follow.status)
  -- Both arms came down to their sides (they stayed held out where they had held hands).
  expect(math.abs(ann:dof("r_shoulder_flexion")) < 0.01 and math.abs(ann:dof("r_elbow_flexion")) < 0.01
         and math.abs(bob:dof("l_shoulder_flexion")) < 0.01 and math.abs(bob:dof("l_elbow_flexion")) < 0.01,
         string.format("the arms hang: ann's shoulder %.2f, bob's %.2f rad", ann:dof("r_shoulder_flexion"),
                       bob:dof("l_shoulder_flexion")))
end)

test("a give or a hold that fails to start lets the partner's action end", function()
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1,
                             at = {-0.2, 1.05, 0.38} }
  -- Ann does not hold the cup: her give fails at its start, Bob's receive must not wait.
  local g = ann:give{ object = cup, to = bob }
  local r = bob:actions()[#bob:actions()]
  expect(r.kind == "receive", "bob receives: " .. r.kind)
  expect(run_until(function() return g.status == "failed" and r.status == "failed" end, 1),
         "both end: give " .. g.status .. ", receive " .. r.status)
  expect(g.error:find("does not hold") ~= nil, g.error)
  expect(r.error:find("giver") ~= nil, tostring(r.error))
  -- Carl's hand is out of Ann's reach: the hold fails, the follower ends too.
  local carl = troupe.actor{ name = "carl", at = {3, 0, 0} }
  local h = ann:hold_hand{ other = carl }
  local f = carl:actions()[1]
  expect(f.kind == "follow_hand", "carl follows")
  expect(run_until(function() return h.status == "failed" and f.status == "completed" end, 1),
         "both end: hold " .. h.status .. ", follow " .. f.status)
end)
