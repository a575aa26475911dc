-- The busy plaza of docs/images/plaza.png: four streams of 12 actors cross a 12 m square
-- with four planters in it, as in plaza.lua (four streams of 50) but small enough to
-- render on a CPU. Rendered with the navigation debug view:
--   troupe render scripts/bench/plaza_picture.lua docs/images/plaza.png --at 5.5 \
--     --debug nav --size 1000x660 --camera fixed:0,13,11:0,0,-0.3 --no-labels
-- Like plaza.lua, the streams jam in the middle (docs/navigation.md, Limits).
for i, c in ipairs({ {-2.5, -2.5}, {2.5, -2.5}, {2.5, 2.5}, {-2.5, 2.5} }) do
  troupe.object{ name = "planter" .. i, shape = "box", size = {1.2, 0.7, 1.2}, at = {c[1], 0.35, c[2]}, mass = 200 }
end
-- Stream s starts in a 4 × 3 block outside one edge and goes to the opposite one.
local streams = { {1, 0}, {-1, 0}, {0, 1}, {0, -1} }
for s, d in ipairs(streams) do
  local side = { -d[2], d[1] }
  for k = 0, 11 do
    local row, col = k // 4, k % 4
    local lateral = (col - 1.5) * 1.0 + (s <= 2 and 0.3 or -0.3)
    local back = 6 + row * 1.0
    local x, z = -d[1] * back + side[1] * lateral, -d[2] * back + side[2] * lateral
    local gx, gz = d[1] * (back - 1) + side[1] * lateral, d[2] * (back - 1) + side[2] * lateral
    local a = troupe.actor{ name = string.format("s%d_%02d", s, k), at = {x, 0, z},
                            facing = math.deg(math.atan(d[1], d[2])) }
    a:behave(function(self)
      self:walk{ to = { gx, 0, gz }, speed = 1.3 }:wait()
    end)
  end
end
