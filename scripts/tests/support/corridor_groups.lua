-- Two groups meeting head-on in a corridor, for scripts/tests/avoidance.lua
-- (require("support.corridor_groups")) and, beside this file, corridors.lua
-- (require("corridor_groups")): a corridor `width` m
-- wide (walls 0.2 m thick along z from −6 to 6 m), `n` walkers a side in rows 0.9 m
-- apart of as many abreast as fit `spacing` m apart, the first rows `first` m from the
-- middle, each bound 8 m beyond the middle (0.9 m more a row back), the goals `spread` m
-- apart across. Returns the actors, their walks and goals {x, z}.
return function(width, n, spread, spacing, first)
  local h = width / 2 + 0.1
  troupe.wall{ from = { -h, -6 }, to = { -h, 6 }, thickness = 0.2 }
  troupe.wall{ from = { h, -6 }, to = { h, 6 }, thickness = 0.2 }
  local cols = math.max(1, math.floor((width - 0.3) / spacing))
  local actors, walks, goals = {}, {}, {}
  for i = 1, 2 * n do
    local side = i <= n and -1 or 1
    local k = (i - 1) % n
    local col, row = k % cols, k // cols
    local x, z = (col - (cols - 1) / 2) * spacing, side * (first + row * 0.9)
    actors[i] = troupe.actor{ name = (side < 0 and "a" or "b") .. (k + 1), at = { x, 0, z },
                              facing = side < 0 and 0 or 180 }
    goals[i] = { (k - (n - 1) / 2) * spread, -side * (8 + row * 0.9) }
  end
  for i, a in ipairs(actors) do walks[i] = a:walk{ to = { goals[i][1], 0, goals[i][2] } } end
  return actors, walks, goals
end
