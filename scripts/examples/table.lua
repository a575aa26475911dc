-- A table with an object of every shape: Ann grasps each in turn (the grasp type comes
-- from the decision table of thesis 4.3.2), lifts it, and puts it back.
-- Run: troupe run scripts/examples/table.lua --until-idle
local ann = troupe.actor{ name = "ann" }
troupe.object{ name = "table", shape = "box", size = {1.0, 0.95, 0.4}, at = {0, 0.475, 0.62}, mass = 20 }

local top = 0.95
local things = {
  troupe.object{ name = "brick",  shape = "box", size = {0.06, 0.1, 0.06}, at = {-0.3, top + 0.05, 0.45} },
  troupe.object{ name = "ball",   shape = "sphere", radius = 0.04, at = {-0.15, top + 0.04, 0.45} },
  troupe.object{ name = "cup",    shape = "cylinder", radius = 0.035, height = 0.12, at = {0.0, top + 0.06, 0.45} },
  troupe.object{ name = "vase",   shape = "frustum", bottom_radius = 0.03, top_radius = 0.042, height = 0.11,
                 at = {0.15, top + 0.055, 0.45} },
  troupe.object{ name = "egg",    shape = "ellipsoid", radii = {0.035, 0.05, 0.03}, at = {0.3, top + 0.05, 0.45} },
}

ann:behave(function(self)
  for _, thing in ipairs(things) do
    local plan, why = troupe.plan_grasp(self, thing)
    if not plan then
      print(thing.name .. ": " .. why)
    else
      print(thing.name .. " (" .. thing.shape .. "): " .. plan.type .. " with the " .. plan.hands[1].hand .. " hand")
      local home = thing:position()
      local g = self:grasp{ object = thing, duration = 0.8 }
      if g:wait() == "completed" then
        local lift = {home[1], home[2] + 0.1, home[3] - 0.05}
        self:manipulate{ object = thing, keys = { { t = 0.6, at = lift } } }:wait()
        local p = self:place{ object = thing, at = home, duration = 0.6 }
        if p:wait() ~= "completed" then print("  place: " .. tostring(p.error)) end
      else
        print("  grasp: " .. tostring(g.error))
      end
    end
  end
  print("done at t = " .. troupe.time())
end)
