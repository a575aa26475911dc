-- Common gestures as sequences, for `local gestures = require("gestures")`.
local gestures = {}

-- A bow from the lower spine: `depth` radians (default 0.5) over `time` seconds (default 1.8).
function gestures.bow(depth, time)
  depth, time = depth or 0.5, time or 1.8
  local q = time / 3
  return troupe.sequence{
    name = "bow",
    vl5_flexion       = { {0, 0}, {q, depth},       {2 * q, depth},       {time, 0} },
    vt12_flexion      = { {0, 0}, {q, depth * 0.4}, {2 * q, depth * 0.4}, {time, 0} },
    skullbase_flexion = { {0, 0}, {q, depth * 0.6}, {2 * q, depth * 0.6}, {time, 0} },
  }
end

-- `count` nods of the head, each `period` seconds long.
function gestures.nod(count, period)
  count, period = count or 2, period or 0.6
  ---@type number[][]
  local keys = { {0, 0} }
  for i = 1, count do
    keys[#keys + 1] = { (i - 0.5) * period, 0.35 }
    keys[#keys + 1] = { i * period, 0 }
  end
  return troupe.sequence{ name = "nod", skullbase_flexion = keys }
end

-- Turns the head toward a point {x, y, z} (yaw only, relative to the actor's facing),
-- as a held pose for `time` seconds.
function gestures.look_toward(actor, point, time)
  local p = actor:joint_position("skullbase")
  local yaw = math.atan(point[1] - p[1], point[3] - p[3]) - actor:dof("root_yaw")
  yaw = (yaw + math.pi) % (2 * math.pi) - math.pi
  local head = math.max(-0.8, math.min(0.8, yaw * 0.7))
  local neck = math.max(-0.6, math.min(0.6, yaw * 0.3))
  return troupe.sequence{
    name = "look",
    skullbase_torsion = { {0, head}, {time or 1, head} },
    vc4_torsion       = { {0, neck}, {time or 1, neck} },
  }
end

return gestures
