-- Where and why the plaza jams (docs/navigation.md, Limits): the scene of
-- scripts/tests/plaza.lua, run for DURATION (120 s), printing every 2.5 s how many walkers stand
-- (slower than 0.1 m/s, away from their goal) and, for each stream, who blocks whom:
-- the nearest actor ahead of a standing walker (within 60° of the way to its goal), its
-- stream, the gap between their body discs, and whether it stands too. Run it with
--   troupe test scripts/tests/support/plaza_jam.lua
local RADIUS = 0.28
-- Seconds to watch.
local DURATION = 120

test("four streams of 50 in the plaza: who stands, and behind whom", function()
  local plaza = require("plaza_streams")
  local actors, walks, goals, stream = {}, {}, {}, {}
  for i, w in ipairs(plaza.build(plaza.BUSY)) do
    actors[i] = w.actor
    goals[i] = { w.gx, w.gz }
    stream[i] = w.stream
  end
  for i, a in ipairs(actors) do
    walks[i] = a:walk{ to = { goals[i][1], 0, goals[i][2] }, speed = 1.3 }
  end
  local last, speed = {}, {}
  for i, a in ipairs(actors) do local p = a:position(); last[i] = { p[1], p[3] }; speed[i] = 1 end
  local dt, tick = 1 / troupe.rate(), 0
  local every = math.floor(2.5 / dt + 0.5)
  local function standing(i, p)
    local away = math.sqrt((p[1] - goals[i][1])^2 + (p[2] - goals[i][2])^2) > 0.2
    return walks[i].status == "active" and away and speed[i] < 0.1
  end
  run_until(function()
    tick = tick + 1
    local pos = {}
    for i, a in ipairs(actors) do
      local p = a:position()
      pos[i] = { p[1], p[3] }
      -- A smoothed speed: the gait's own sway is not a stop.
      local v = math.sqrt((pos[i][1] - last[i][1])^2 + (pos[i][2] - last[i][2])^2) / dt
      speed[i] = 0.9 * speed[i] + 0.1 * v
      last[i] = pos[i]
    end
    if tick % every ~= 0 then return false end
    local arrived, stood, same, cross, none, chains = 0, 0, 0, 0, 0, 0
    local overlaps, deepest = 0, 0.0
    for i = 1, #actors do
      for j = i + 1, #actors do
        local gap = math.sqrt((pos[i][1] - pos[j][1])^2 + (pos[i][2] - pos[j][2])^2) - 2 * RADIUS
        if gap < 0 then overlaps = overlaps + 1; deepest = math.max(deepest, -gap) end
      end
    end
    local examples = {}
    for i = 1, #actors do
      if walks[i].status == "completed" then arrived = arrived + 1 end
      if standing(i, pos[i]) then
        stood = stood + 1
        local gx, gz = goals[i][1] - pos[i][1], goals[i][2] - pos[i][2]
        local gl = math.sqrt(gx * gx + gz * gz)
        local best, bj = math.huge, nil
        for j = 1, #actors do
          if j ~= i then
            local dx, dz = pos[j][1] - pos[i][1], pos[j][2] - pos[i][2]
            local d = math.sqrt(dx * dx + dz * dz)
            if d < 2 and (dx * gx + dz * gz) / (d * gl) > 0.5 and d < best then best, bj = d, j end
          end
        end
        if not bj then
          none = none + 1
        else
          if stream[bj] == stream[i] then same = same + 1 else cross = cross + 1 end
          if standing(bj, pos[bj]) then chains = chains + 1 end
          if #examples < 4 then
            examples[#examples + 1] = string.format("%s behind %s (gap %.2f m, %s)", actors[i].name,
              actors[bj].name, best - 2 * RADIUS, standing(bj, pos[bj]) and "standing" or "moving")
          end
        end
      end
    end
    print(string.format("t = %4.1f s: %3d arrived, %3d standing: behind their own stream %d, another stream %d, nobody within 2 m %d; %d of them behind someone standing; %d disc overlaps (deepest %.3f m)",
      troupe.time(), arrived, stood, same, cross, none, chains, overlaps, deepest))
    for _, e in ipairs(examples) do print("    " .. e) end
    return false
  end, DURATION)
end)
