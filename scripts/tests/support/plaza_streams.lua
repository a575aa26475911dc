-- The plaza's scene, shared by scripts/tests/plaza.lua and, beside this file, plaza_jam.lua,
-- plaza_layouts.lua and plaza_picture.lua: a planter
-- near each corner of a square, and four streams of walkers, each starting in a block
-- outside one edge, bound for the opposite edge. Nobody walks yet: the caller says how.
local M = {}

-- Makes the planters and the actors. `o.planter`: the planters' centres' distance from
-- the middle along x and z; `o.planter_size`: their box; `o.per_stream` actors a stream,
-- in rows of `o.columns` 1 m apart, the first row `o.back` m from the middle, each bound
-- for the mirror image of its place beyond the middle, the block spread to rows and
-- columns `o.spread` m apart (the first row the furthest, the last `o.back` − 1 m from
-- the middle). Returns one
-- entry per actor, in the order made: { actor, stream, x, z (start), gx, gz (goal) }.
function M.build(o)
  local size = o.planter_size
  for i, c in ipairs({ {-1, -1}, {1, -1}, {1, 1}, {-1, 1} }) do
    troupe.object{ name = "planter" .. i, shape = "box", size = size,
                   at = {c[1] * o.planter, size[2] / 2, c[2] * o.planter}, mass = 200 }
  end
  local walkers = {}
  local streams = { {1, 0}, {-1, 0}, {0, 1}, {0, -1} }
  for s, d in ipairs(streams) do
    local side = { -d[2], d[1] }
    for k = 0, o.per_stream - 1 do
      local row, col = k // o.columns, k % o.columns
      local lateral = (col - (o.columns - 1) / 2) * 1.0 + (s <= 2 and 0.3 or -0.3)
      local back = o.back + row * 1.0
      local x, z = -d[1] * back + side[1] * lateral, -d[2] * back + side[2] * lateral
      -- The block crosses whole, spreading out: its first row ends furthest, its last
      -- nearest, `o.spread` m apart, so that one who arrives late can pass between
      -- those who stand at their places already.
      local rows = math.ceil(o.per_stream / o.columns)
      local far = o.back - 1 + (rows - 1 - row) * o.spread
      local wide = (col - (o.columns - 1) / 2) * o.spread + (s <= 2 and 0.3 or -0.3)
      local gx, gz = d[1] * far + side[1] * wide, d[2] * far + side[2] * wide
      local a = troupe.actor{ name = string.format("s%d_%02d", s, k), at = {x, 0, z},
                              facing = math.deg(math.atan(d[1], d[2])) }
      walkers[#walkers + 1] = { actor = a, stream = s, x = x, z = z, gx = gx, gz = gz }
    end
  end
  return walkers
end

-- Whether every walk in `walks` has ended (completed or failed).
function M.ended(walks)
  for _, w in ipairs(walks) do
    if w.status ~= "completed" and w.status ~= "failed" then return false end
  end
  return true
end

-- How many of `walks` completed, and the mean detour over them (`walked[i]` /
-- `straight[i]` − 1: the way walker i walked against the straight way to its goal).
function M.tally(walks, walked, straight)
  local arrived, detour = 0, 0.0
  for i in ipairs(walks) do
    if walks[i].status == "completed" then arrived = arrived + 1 end
    detour = detour + walked[i] / straight[i] - 1
  end
  return arrived, detour / #walks
end

-- The plaza of plaza.lua and plaza_jam.lua: 20 m × 20 m, four streams of 50.
M.BUSY = { planter = 4, planter_size = {1.5, 0.8, 1.5}, per_stream = 50, columns = 5, back = 11,
           spread = 1.5 }

return M
