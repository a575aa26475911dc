-- Script errors, runaway scripts and allocation bombs stop only their own behavior. The
-- tests wait for the failing behaviors (`b:wait()`): a failure a test waits for is the
-- test's to judge, any other fails the test.

test("a script error stops only that actor's behavior", function()
  local bad = troupe.actor{ name = "bad" }
  local good = troupe.actor{ name = "good", at = {2, 0, 0} }
  local ticks = 0
  local b = bad:behave(function() wait(0.1); local x = nil; return x.field end)
  good:behave(function() while true do ticks = ticks + 1; wait(0.01) end end)
  b:wait()
  run(0.4)
  expect(bad:behavior_status() == "failed", "bad failed")
  expect(bad:behavior_error():find("safety.lua:%d+") ~= nil, "the error names file:line: " .. bad:behavior_error())
  expect(bad:behavior_error():find("traceback") ~= nil, "with a traceback")
  expect(good:behavior_status() == "running" and ticks > 40, "good keeps going")
end)

test("a runaway script is stopped within the tick", function()
  local loop = troupe.actor{ name = "loop" }
  local b = loop:behave(function() wait(0.05); while true do end end)
  b:wait()
  expect(troupe.time() < 0.1, "within the tick")
  expect(loop:behavior_status() == "failed", "runaway stopped")
  expect(loop:behavior_error():find("instruction budget") ~= nil, loop:behavior_error())
end)

test("an allocation bomb hits the memory limit", function()
  local bomb = troupe.actor{ name = "bomb" }
  local b1 = bomb:behave(function()
    local t = {}
    for i = 1, 1e9 do t[i] = string.rep("x", 1024) .. i end
  end)
  local bomb2 = troupe.actor{ name = "bomb2", at = {2, 0, 0} }
  local b2 = bomb2:behave(function() wait(0.05); local s = string.rep("y", 1 << 28) end)
  b1:wait()
  b2:wait()
  expect(bomb:behavior_status() == "failed", "bomb failed")
  expect(bomb:behavior_error():find("memory") ~= nil, bomb:behavior_error())
  expect(bomb2:behavior_status() == "failed", "one huge allocation fails too")
  expect(bomb2:behavior_error():find("memory") ~= nil, bomb2:behavior_error())
end)

test("the sandbox has no io, os, debug, package or load", function()
  for _, name in ipairs{ "io", "os", "debug", "package", "load", "loadfile", "dofile" } do
    expect(_G[name] == nil, name .. " is not available")
  end
end)

test("bad arguments give errors naming them", function()
  local ann = troupe.actor{ name = "ann" }
  local seq = troupe.sequence{ r_elbow_flexion = { {0, 0}, {1, 1} } }
  local function fails(f, needle)
    local ok, err = pcall(f)
    expect(not ok, "should fail: " .. needle)
    expect(tostring(err):find(needle, 1, true) ~= nil, "error mentions `" .. needle .. "`: " .. tostring(err))
  end
  fails(function() ann:play(seq, { wieght = 1 }) end, "unknown option `wieght`")
  fails(function() ann:play(seq, { weight = 2, mode = "weighted" }) end, "weight")
  fails(function() ann:play(seq, { weight = "heavy" }) end, "option `weight` must be a number")
  fails(function() ann:play(seq, { scope = "tail" }) end, "unknown scope `tail`")
  fails(function() ann:play(seq, { mode = "polite" }) end, "unknown priority mode `polite`")
  fails(function() ann:play(seq, { duration = -1 }) end, "duration")
  fails(function() ann:play("missing.trk") end, "missing.trk")
  fails(function() ann:dof("r_elbow_twist") end, "unknown DOF `r_elbow_twist`")
  fails(function() ann:joint_position("r_antenna") end, "unknown joint `r_antenna`")
  fails(function() troupe.actor{ name = "ann" } end, "already exists")
  fails(function() troupe.actor{ name = "x", template = "robot" } end, "unknown body template `robot`")
  fails(function() troupe.object{ name = "o", shape = "sphere", radius = -1 } end, "radius")
  fails(function() troupe.actor{ name = "y", colour = "red" } end, "unknown field `colour`")
  fails(function() troupe.sequence{ r_elbow_flexion = { {1, 0}, {0, 1} } } end, "does not follow")
end)
