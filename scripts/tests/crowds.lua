-- Walkers in each other's way (docs/navigation.md, "The plaza: crossing streams"): who
-- gives way where two ways cross, and a walker that leaves its plan to go round people
-- standing in its way. Small scenes of the plaza's rules, on 1 and 2 threads.

test("two ways cross: the walker along x waits for the one along z", function()
  -- Both would reach the crossing at (0, 0) at the same moment.
  local ann = troupe.actor{ name = "ann", at = {-6, 0, 0}, facing = 90 }
  local bob = troupe.actor{ name = "bob", at = {0, 0, -6}, facing = 0 }
  local wa = ann:walk{ to = {6, 0, 0}, speed = 1.3 }
  local wb = bob:walk{ to = {0, 0, 6}, speed = 1.3 }
  local deepest, ann_at, bob_at = 0.0, nil, nil
  run_until(function()
    deepest = math.max(deepest, (troupe.deepest_overlap{ discs = true }))
    local a, b = ann:position(), bob:position()
    -- Who passes the crossing first.
    if not ann_at and a[1] > 0 then ann_at = troupe.time() end
    if not bob_at and b[3] > 0 then bob_at = troupe.time() end
    return wa.status == "completed" and wb.status == "completed"
  end, 30)
  print(string.format("crossing: bob passes at %.2f s, ann at %.2f s; deepest disc overlap %.4f m",
    bob_at or -1, ann_at or -1, deepest))
  expect(wa.status == "completed" and wb.status == "completed", "both arrive")
  expect(bob_at and ann_at and bob_at + 0.5 < ann_at, "bob (along z) has the way and passes first")
  expect(deepest == 0, string.format("discs overlapped %.4f m", deepest))
end)

test("a row of people standing across the way: the walker goes round it", function()
  -- Five stand shoulder to shoulder across the way, 0.9 m apart: the gaps (0.34 m) are
  -- narrower than a body, so the walk must leave its straight plan.
  for i = -2, 2 do
    troupe.actor{ name = "stander" .. (i + 3), at = {i * 0.9, 0, 0}, facing = 180 }
  end
  local ann = troupe.actor{ name = "ann", at = {0, 0, -4}, facing = 0 }
  local walk = ann:walk{ to = {0, 0, 4}, speed = 1.2 }
  local deepest = 0.0
  local ok = run_until(function()
    deepest = math.max(deepest, (troupe.deepest_overlap{ discs = true }))
    return walk.status == "completed" or walk.status == "failed"
  end, 30)
  local p = ann:position()
  print(string.format("row: ann arrives at %.1f s, %.2f m from her goal; deepest disc overlap %.4f m",
    troupe.time(), math.sqrt(p[1]^2 + (p[3] - 4)^2), deepest))
  expect(ok and walk.status == "completed", "ann arrives")
  expect(math.sqrt(p[1]^2 + (p[3] - 4)^2) < 0.1, "at her goal")
  expect(deepest <= 0.01, string.format("discs overlapped %.4f m", deepest))
end)

test("a loose line sets off one behind another: feet keep up with their bodies", function()
  -- Four walk to a counter, each setting off 0.6 s after the one ahead, 0.9 m behind it.
  -- A landing ahead of a walker falls where the one ahead stands now but will have left:
  -- it lands there, and where it is pinched after all (the one ahead slowing down) the
  -- body waits for its feet. Before, such a foot stepped in place while the body walked on
  -- along its plan: a pelvis sank 0.23 m to reach a foot left a stride behind, and an
  -- ankle went 0.11 m below its standing height (the sole under the floor). What is left
  -- (docs/navigation.md): a pelvis lowered 0.13 m and a foot short by 2 cm as a walker
  -- that closed on a slowing one catches up with its feet.
  troupe.object{ name = "counter", shape = "box", size = {1.6, 0.95, 0.5}, at = {0, 0.475, 0}, mass = 80 }
  local people, walks = {}, {}
  for i = 1, 4 do
    people[i] = troupe.actor{ name = "p" .. i, at = {-3.5 - 0.9 * i, 0, -2.5 + 0.3 * i}, facing = 90 }
  end
  local ankle = people[1]:joint_position("l_ankle")[2]
  local pelvis = people[1]:position()[2]
  for i = 1, 4 do
    people[i]:behave(function(self)
      wait(0.6 * (i - 1))
      walks[i] = self:walk{ to = {0, 0, -0.72 - 0.75 * (i - 1)}, heading = 0 }
    end)
  end
  local lowest_ankle, lowest_pelvis, who = math.huge, math.huge, nil
  local ok = run_until(function()
    for i = 1, 4 do
      local p = people[i]
      local y = math.min(p:joint_position("l_ankle")[2], p:joint_position("r_ankle")[2])
      if y < lowest_ankle then lowest_ankle, who = y, p.name end
      lowest_pelvis = math.min(lowest_pelvis, p:position()[2])
    end
    for i = 1, 4 do
      if not walks[i] or walks[i].status ~= "completed" then return false end
    end
    return true
  end, 30)
  print(string.format("loose line: lowest ankle %.3f m (%s; %.3f standing), lowest root %.3f m (%.3f standing), all in by %.1f s",
    lowest_ankle, who, ankle, lowest_pelvis, pelvis, troupe.time()))
  expect(ok, "all four arrive")
  expect(lowest_ankle > ankle - 0.025, string.format("an ankle went %.3f m below its standing height", ankle - lowest_ankle))
  expect(lowest_pelvis > pelvis - 0.15, string.format("a pelvis sank %.3f m", pelvis - lowest_pelvis))
end)
