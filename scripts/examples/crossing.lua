-- Four people cross a square: their paths cross in the middle at different moments.
-- Ann waves (a weighted wave on her right arm) while she walks; Cid, a child, hurries
-- with a run-like gait; Dee follows a keyframed Global_motion path (6.4.2).
-- Run:    troupe run scripts/examples/crossing.lua --until-idle
-- Record: troupe run scripts/examples/crossing.lua --until-idle --record out/crossing.trk
local ann = troupe.actor{ name = "ann", at = {-3, 0, -0.4}, facing = 90 }
local bob = troupe.actor{ name = "bob", height = 1.85, at = {0.4, 0, -3}, facing = 0 }
local cid = troupe.actor{ name = "cid", template = "child", at = {2.6, 0, 2.6}, facing = -135 }
local dee = troupe.actor{ name = "dee", height = 1.62, at = {-2.5, 0, 2.5}, facing = 135 }

ann:behave(function(self)
  local walk = self:walk{ to = {3, 0, 0.4}, speed = 1.2 }
  wait(1.0)
  local wave = self:play("wave.trk", { mode = "weighted", weight = 0.9, scope = "right_arm",
                                       ease_in = 0.3, ease_out = 0.3 })
  wait_all(walk, wave)
  print(string.format("ann arrived at t = %.2f s", troupe.time()))
end)

bob:behave(function(self)
  wait(1.5)
  -- A path around the middle, ending facing back toward the others.
  self:walk{ path = {{0.8, -1}, {-0.6, 1.2}, {-0.4, 3}}, speed = 1.4, heading = 180 }:wait()
  print(string.format("bob arrived at t = %.2f s", troupe.time()))
end)

cid:behave(function(self)
  wait(0.5)
  self:walk{ to = {-2.4, 0, -2.4}, speed = 1.5, run = 0.6, arm_swing = 1.4 }:wait()
  print(string.format("cid arrived at t = %.2f s", troupe.time()))
end)

dee:behave(function(self)
  local global_motion = troupe.sequence{
    root_x = { {0, 0}, {2.5, 1.8}, {5, 4.6} },
    root_z = { {0, 0}, {2.5, -2.8}, {5, -4.8} },
  }
  wait(2.0)
  self:walk{ follow = global_motion, pelvis = 1.8 }:wait()
  print(string.format("dee arrived at t = %.2f s", troupe.time()))
end)
