-- What the solids scenario tests share (require("support.solids")): watching the deepest
-- interpenetration of solids while something runs, and how fast an action turns joints.
local M = {}

-- Runs `fn` every tick until it returns true (or `limit` s), watching the deepest solid
-- interpenetration (troupe.deepest_overlap): returns whether `fn` did, the deepest depth
-- and what it was between.
function M.watch(fn, limit)
  local deepest, between = 0.0, "nothing"
  local ok = run_until(function()
    local d, a, b, sa, sb = troupe.deepest_overlap()
    if d > deepest then
      deepest = d
      between = string.format("%s's %s and %s's %s", a, sa, b, tostring(sb))
    end
    return fn()
  end, limit)
  return ok, deepest, between
end

-- Ann at the origin facing +Z; Bob 0.75 m to her right, `z` metres in front of her,
-- facing across her front and holding his left hand out to `hand`; a cup (not an
-- obstacle) at `cup`. Returns ann, bob and the cup once Bob's arm is out.
function M.arm_across(z, hand, cup)
  local ann = troupe.actor{ name = "ann" }
  local bob = troupe.actor{ name = "bob", at = {-0.75, 0, z}, facing = 90 }
  local object = troupe.object{ name = "cup", shape = "cylinder", radius = 0.04, height = 0.1,
    at = cup, obstacle = false }
  local held = bob:reach{ hand = "left", target = hand, duration = 1 }
  held:wait()
  expect(held.status == "completed", "bob holds his arm out: " .. tostring(held.error))
  return ann, bob, object
end

-- Whether action `a` has ended (completed, failed or cancelled).
function M.ended(a)
  return a.status ~= "active" and a.status ~= "pending"
end

-- Steps tick by tick until action `a` ends, measuring how fast the DOFs of `actor`'s
-- scope `scope` turn while `a` is active (the tick it ends on left out, unless
-- `with_last`): returns the fastest speed (rad/s) and the DOF.
function M.fastest_dof(actor, scope, a, with_last)
  local names = actor:dofs(scope)
  local function posture()
    local q = {}
    for i, n in ipairs(names) do q[i] = actor:dof(n) end
    return q
  end
  local dt = 1 / troupe.rate()
  local last, fastest, where = posture(), 0, ""
  while not M.ended(a) do
    wait(dt)
    local q = posture()
    if a.status == "active" or with_last then
      for i, n in ipairs(names) do
        local speed = math.abs(q[i] - last[i]) / dt
        if speed > fastest then fastest, where = speed, n end
      end
    end
    last = q
  end
  return fastest, where
end

return M
