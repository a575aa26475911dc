-- The standard crowd scene of `troupe bench` (docs/PERFORMANCE.md).
-- Every actor loops: walk to a parcel near it while waving (a weighted keyframe wave on
-- the right arm over the walk's arm swing), stop, reach for the parcel, look at a
-- neighbour, and go again. Parcels are picked within a few metres, so the mix of walking,
-- reaching and looking is the same at every crowd size. The number of actors comes from
-- `BENCH.actors` when `troupe bench` runs it; run alone it has 24:
--   troupe run scripts/bench/crowd.lua --seconds 20 --threads 2
local count = (BENCH and BENCH.actors) or 24

-- Parcels on pillars, one per four actors, on a square field that grows with the crowd
-- so the density stays the same (about 4 m² per actor).
local side = math.max(4, math.sqrt(count * 4))
local parcels = {}
for p = 1, math.max(2, count // 4) do
  local x, z = (math.random() - 0.5) * side, (math.random() - 0.5) * side
  troupe.object{ name = "pillar" .. p, shape = "box", size = {0.3, 0.95, 0.3}, at = {x, 0.475, z}, mass = 50 }
  parcels[p] = { object = troupe.object{ name = "parcel" .. p, shape = "box", size = {0.2, 0.1, 0.2}, at = {x, 1.0, z} }, x = x, z = z }
end

-- A random parcel between 1 and 5 m away (the nearest one if none is).
local function pick_parcel(x, z)
  local near, nearest, best = {}, nil, math.huge
  for _, p in ipairs(parcels) do
    local d = math.sqrt((p.x - x)^2 + (p.z - z)^2)
    if d >= 1 and d <= 5 then near[#near + 1] = p end
    if d < best then nearest, best = p, d end
  end
  if #near == 0 then return nearest end
  return near[math.random(#near)]
end

local wave = troupe.sequence{
  name = "crowd wave", loop = true,
  r_shoulder_abduction = { {0, 1.4}, {0.6, 1.6}, {1.2, 1.4} },
  r_elbow_flexion = { {0, 0.8}, {0.3, 1.4}, {0.6, 0.8}, {0.9, 1.4}, {1.2, 0.8} },
}

local actors = {}
for i = 1, count do
  actors[i] = troupe.actor{
    name = "a" .. i,
    at = { (math.random() - 0.5) * side, 0, (math.random() - 0.5) * side },
    facing = math.random(0, 359),
  }
end

for i, actor in ipairs(actors) do
  local neighbour = actors[i % count + 1]
  actor:behave(function(self)
    wait(math.random() * 0.5)
    while true do
      -- Walk to a parcel near by (the walk plans around the pillars and ends within
      -- reach, facing it), waving on the way.
      local here = self:position()
      local parcel = pick_parcel(here[1], here[3]).object
      -- The walk first: a default-mode action waits for running actions on its scope.
      local walking = self:walk{ to = parcel, speed = 1.0 + 0.6 * math.random() }
      local waving = self:play(wave, { scope = "right_arm", mode = "weighted", weight = 0.6, ease_in = 0.4, ease_out = 0.3 })
      walking:wait()
      waving:cancel()
      -- Reach for the parcel, then look at the neighbour for a moment.
      self:reach{ hand = "right", target = parcel, duration = 0.8 }:wait()
      self:look_at{ target = neighbour, duration = 1.0, ease_in = 0.2, ease_out = 0.2 }:wait()
    end
  end)
end
