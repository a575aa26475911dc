-- The busy plaza of docs/images/plaza.png: four streams of 12 actors cross a 12 m square
-- with four planters in it, as in plaza.lua (four streams of 50) but small enough to
-- render on a CPU. Rendered with the navigation debug view:
--   troupe render scripts/tests/support/plaza_picture.lua docs/images/plaza.png --at 5.5 \
--     --debug nav --size 1000x660 --camera fixed:0,13,11:0,0,-0.3 --no-labels
-- Stream s starts in a 4 × 3 block outside one edge and goes to the opposite one.
local plaza = require("plaza_streams")
local walkers = plaza.build{ planter = 2.5, planter_size = {1.2, 0.7, 1.2}, per_stream = 12, columns = 4, back = 6,
                               spread = 1.0 }
for _, w in ipairs(walkers) do
  w.actor:behave(function(self)
    self:walk{ to = { w.gx, 0, w.gz }, speed = 1.3 }:wait()
  end)
end
