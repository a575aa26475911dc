-- What the solids scenario tests share (require("support.solids")): watching the deepest
-- interpenetration of solids while something runs.
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

-- Whether action `a` has ended (completed, failed or cancelled).
function M.ended(a)
  return a.status ~= "active" and a.status ~= "pending"
end

return M
