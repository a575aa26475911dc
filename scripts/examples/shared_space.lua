-- A shared space (issue 18, docs/navigation.md). A room with a table and a wall with a
-- doorway: Ann walks round the table to the cup and picks it up; six people on a circle
-- swap places through the middle, stepping aside for one another; Bob walks through the
-- doorway to greet Ann.
--   troupe run scripts/examples/shared_space.lua --until-idle
troupe.object{ name = "table", shape = "box", size = {1.6, 0.75, 0.8}, at = {0, 0.375, 3}, mass = 30 }
local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1, at = {0.3, 0.8, 2.75} }
troupe.wall{ from = {-6, 6}, to = {-0.6, 6}, thickness = 0.15, height = 2.2 }
troupe.wall{ from = {0.6, 6}, to = {6, 6}, thickness = 0.15, height = 2.2 }

local ann = troupe.actor{ name = "ann", at = {0, 0, 5.2}, facing = 180 }
local bob = troupe.actor{ name = "bob", at = {1.5, 0, 8.5}, facing = 180 }

ann:behave(function(self)
  self:walk{ to = cup, speed = 1.1 }:wait()
  self:grasp{ object = cup, hand = "right" }:wait()
end)

bob:behave(function(self)
  wait(1)
  local w = self:walk{ to = ann, speed = 1.2 }
  w:wait()
  print(string.format("bob: %s, %.2f m from ann", w.status,
    math.sqrt((self:position()[1] - ann:position()[1])^2 + (self:position()[3] - ann:position()[3])^2)))
end)

for i = 1, 6 do
  local a = (i - 1) * math.pi / 3
  local x, z = -4 + 2.5 * math.sin(a), 2.5 * math.cos(a)
  local walker = troupe.actor{ name = "w" .. i, at = {x, 0, z}, facing = math.deg(a) + 180 }
  walker:behave(function(self)
    local w = self:walk{ to = {-8 - x, 0, -z}, speed = 1.2 }
    w:wait()
    print(string.format("%s: %s", self.name, w.status))
  end)
end
