-- The niche of scripts/tests/navigation.lua ("… with none free it waits its turn") on
-- fourteen variants, to measure what the stand-offs do with a walker at a niche's mouth
-- and the one in it coming out (docs/navigation.md, "Limits"). The scene is chaotic: the
-- test's own numbers came out, but moving bob's start or cid's place by a millimetre
-- can leave the two facing each other in the niche for good. Each variant is one test
-- printing one line: whether cid got out by 40 s, whether bob's walk ended, and where
-- the two stand. It checks nothing (`troupe test` counts every variant as passed):
--   troupe test scripts/tests/support/niche_variants.lua

-- (bob's start z, cid's x): the test's own first, then moved by 1 mm to 10 cm.
local VARIANTS = {
  { -3, 10 }, { -3.001, 10 }, { -3.002, 10 }, { -2.999, 10 }, { -3.01, 10 }, { -3, 10.001 },
  { -3, 9.999 }, { -2.99, 10 }, { -3.02, 10 }, { -3.05, 10.02 }, { -2.95, 9.97 }, { -3.1, 10 },
  { -2.9, 10.03 }, { -3.03, 9.98 },
}

for _, v in ipairs(VARIANTS) do
  local bob_z, cid_x = v[1], v[2]
  test(string.format("the niche with bob from z %.3f, cid at x %.3f", bob_z, cid_x), function()
    troupe.wall{ from = {9.5, 0}, to = {9.5, 2} }
    troupe.wall{ from = {10.5, 0}, to = {10.5, 2} }
    troupe.wall{ from = {9.5, 2}, to = {10.5, 2} }
    local shelf = troupe.object{ name = "shelf", shape = "box", size = {0.9, 1.2, 0.3}, at = {10, 0.6, 1.8}, mass = 30 }
    local cid = troupe.actor{ name = "cid", at = {cid_x, 0, 1.1} }
    local bob = troupe.actor{ name = "bob", at = {10, 0, bob_z} }
    local b = bob:walk{ to = shelf }
    run(8)
    local c = cid:walk{ to = {12, 0, -1} }
    run_until(function() return c.status ~= "active" end, 40)
    local p, q = bob:position(), cid:position()
    print(string.format("bob from z %.3f, cid at x %.3f: cid %s%s, bob's walk %s; bob at (%.2f, %.2f), cid at (%.2f, %.2f)",
      bob_z, cid_x, c.status == "completed" and "got out" or "still in", c.status == "completed" and
      string.format(" at %.1f s", troupe.time()) or "", b.status, p[1], p[3], q[1], q[3]))
  end)
end
