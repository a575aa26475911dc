-- A crowd gathers round a street performer: twenty-eight people come across a square
-- from every side, a few at a time, each sent to stand 1.5 m from him
-- (`walk{ to = ACTOR }`). The first ring fills; those who find their place taken stand
-- in rows behind it, nobody walking through the ring or standing inside it, and each
-- then watches him (docs/navigation.md, "Destinations").
-- Run:    troupe run scripts/examples/gathering.lua --until-idle
-- Record: troupe run scripts/examples/gathering.lua --until-idle --record out/gathering.trk
local performer = troupe.actor{ name = "performer", height = 1.8, facing = 0 }

-- Juggling: both forearms up and down in turn.
local juggling = troupe.sequence{
  name = "juggling", loop = true,
  r_shoulder_flexion = { {0, 0.5}, {0.4, 0.7}, {0.8, 0.5} },
  l_shoulder_flexion = { {0, 0.7}, {0.4, 0.5}, {0.8, 0.7} },
  r_elbow_flexion = { {0, 1.6}, {0.4, 1.1}, {0.8, 1.6} },
  l_elbow_flexion = { {0, 1.1}, {0.4, 1.6}, {0.8, 1.1} },
}
local count = 28
local arrived = 0

-- He juggles until everyone has come and watched for a while.
performer:behave(function(self)
  local juggle = self:play(juggling, { ease_in = 0.5, ease_out = 0.5 })
  while arrived < count do wait(0.5) end
  wait(8)
  juggle:cancel()
end)

local standing, nearest, farthest = 0, math.huge, 0.0
for i = 1, count do
  local angle = (i - 1) * 2 * math.pi / count + 0.3 * math.random()
  local far = 7 + 3 * math.random()
  local who = troupe.actor{
    name = "p" .. i,
    height = 1.55 + 0.35 * math.random(),
    at = { far * math.cos(angle), 0, far * math.sin(angle) },
    facing = math.deg(math.atan(-math.cos(angle), -math.sin(angle))),
  }
  who:behave(function(self)
    wait(4 * math.random())
    local w = self:walk{ to = performer, distance = 1.5, speed = 1.0 + 0.4 * math.random() }
    if w:wait() == "completed" then
      local p = self:position()
      local d = math.sqrt(p[1] ^ 2 + p[3] ^ 2)
      standing, nearest, farthest = standing + 1, math.min(nearest, d), math.max(farthest, d)
    else
      print(string.format("%s did not get there: %s", self.name, tostring(w.error)))
    end
    arrived = arrived + 1
    if arrived == count then
      print(string.format("%d of %d stand round the performer at t = %.1f s, from %.2f to %.2f m from him",
        standing, count, troupe.time(), nearest, farthest))
    end
    self:look_at{ target = performer, duration = 10 }:wait()
  end)
end
