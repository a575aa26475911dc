-- Waiting, cancelling and events.
local function hold(value, dof, length)
  return troupe.sequence{ [dof or "r_elbow_flexion"] = { {0, value}, {length or 0.5, value} } }
end

test("wait advances simulated time", function()
  local t0 = troupe.time()
  run(0.5)
  expect(math.abs(troupe.time() - t0 - 0.5) < 1e-9, "half a second later")
end)

test("action:wait returns the final status", function()
  local ann = troupe.actor{ name = "ann" }
  local results = {}
  ann:behave(function(self)
    local a = self:play(hold(1.0), { duration = 0.3 })
    results.status = a:wait()
    results.time = troupe.time()
  end)
  run(1)
  expect(results.status == "completed", "completed, got " .. tostring(results.status))
  expect(results.time >= 0.3, "after the duration")
  expect(ann:behavior_status() == "done", "the behavior returned")
end)

test("wait_all and wait_any", function()
  local ann = troupe.actor{ name = "ann" }
  local short = ann:play(hold(1.0, "r_elbow_flexion", 0.2))
  local long = ann:play(hold(1.0, "l_elbow_flexion", 0.6))
  local first = nil
  ann:behave(function()
    first = wait_any(short, long)
    wait_all(short, long)
  end)
  run_until(function() return ann:behavior_status() == "done" end, 2)
  expect(first == short, "the short one ends first")
  expect(long.status == "completed", "wait_all waited for the long one")
end)

test("waits on actions that ended long ago, or end while others wait, resume at once", function()
  local ann = troupe.actor{ name = "ann" }
  local done = ann:play(hold(1.0, "r_elbow_flexion", 0.1))
  run(0.5)
  expect(done.status == "completed", "ended before anyone waited")
  local long = ann:play(hold(1.0, "l_elbow_flexion", 0.4))
  local at = {}
  ann:behave(function()
    local t0 = troupe.time()
    expect(done:wait() == "completed", "the old action's status")
    wait_all(done)
    expect(wait_any(long, done) == done, "the ended one is first")
    at.old = troupe.time() - t0
    expect(long:wait() == "completed", "the long one")
    at.long = troupe.time()
  end)
  run_until(function() return ann:behavior_status() == "done" end, 2)
  -- One tick per wait: each resumes on the tick after it was made.
  expect(math.abs(at.old - 3 / troupe.rate()) < 1e-9, "three waits, three ticks: " .. at.old)
  expect(at.long <= 0.5 + 0.4 + 2 / troupe.rate(), "woken by the end of the long one: " .. at.long)
end)

test("wait_all and wait_any refuse what is not an action, catchably, with the place", function()
  local ann = troupe.actor{ name = "ann" }
  local a = ann:play(hold(0.2, "r_elbow_flexion", 0.1))
  local err
  ann:behave(function()
    local ok, e = pcall(wait_any, a, 5)
    err = { ok, e }
    local ok2, e2 = pcall(function() wait_all({ a, "x" }) end)
    err[3], err[4] = ok2, e2
    local ok3, e3 = pcall(function() wait_any(a, nil, a) end)
    err[5], err[6] = ok3, e3
    local ok4, e4 = pcall(function() wait_all(ann) end)
    err[7], err[8] = ok4, e4
  end)
  run_until(function() return ann:behavior_status() ~= "running" end, 2)
  expect(ann:behavior_status() == "done", "the behavior goes on: " .. ann:behavior_status())
  -- Called by pcall itself, the error has no Lua caller to name.
  expect(err[1] == false and err[2]:find("wait_any: argument 2 must be an action, got integer", 1, true) ~= nil,
         tostring(err[2]))
  expect(err[3] == false and err[4]:find("waits%.lua:%d+: wait_all: argument 2 must be an action, got string") ~= nil,
         tostring(err[4]))
  expect(err[5] == false and err[6]:find("wait_any: argument 2 must be an action, got nil", 1, true) ~= nil,
         tostring(err[6]))
  -- A handle is named for what it is.
  expect(err[7] == false and err[8]:find("wait_all: argument 1 must be an action, got an actor", 1, true) ~= nil,
         tostring(err[8]))
end)

test("wait_until returns false at its timeout", function()
  local got = nil
  local ann = troupe.actor{ name = "ann" }
  ann:behave(function() got = wait_until(function() return false end, 0.25) end)
  run(0.5)
  expect(got == false, "timed out")
end)

test("cancel a pending and a running action", function()
  local ann = troupe.actor{ name = "ann" }
  local later = ann:play(hold(1.0), { delay = 5 })
  local now = ann:play(hold(1.0, "l_elbow_flexion", 10), { ease_out = 0.2 })
  run(0.1)
  later:cancel()
  now:cancel()
  run(0.05)
  expect(later.status == "cancelled", "pending one cancelled at once")
  expect(now.status == "terminating", "running one eases out, got " .. now.status)
  expect(now:wait() == "cancelled", "then ends cancelled")
end)

test("events reach handlers on the next tick", function()
  local ann = troupe.actor{ name = "ann" }
  local seen = {}
  ann:on("action_started", function(a) seen[#seen + 1] = "started " .. a.kind end)
  ann:on("action_completed", function(a) seen[#seen + 1] = "completed " .. a.id end)
  ann:on("action_cancelled", function(a) seen[#seen + 1] = "cancelled" end)
  local a = ann:play(hold(1.0), { duration = 0.1 })
  a:wait()
  run(0.02)
  expect(seen[1] == "started keyframe", tostring(seen[1]))
  expect(seen[2] == "completed " .. a.id, tostring(seen[2]))
  expect(#seen == 2, "exactly two events, got " .. #seen)
end)

test("queries", function()
  local ann = troupe.actor{ name = "ann", at = {1, 0, 2}, height = 1.7 }
  run(0.01)
  local p = ann:position()
  expect(p[1] == 1 and p[3] == 2, "position")
  local hand = ann:joint_position("r_wrist")
  expect(hand[2] > 0.5 and hand[2] < 1.0, "wrist at hip height")
  local arm = ann:dofs("right_arm")
  expect(#arm == 9 and arm[1] == "r_sternoclavicular_elevation", "dofs of a scope in order")
  ann:pose{ r_elbow_flexion = 1.0 }
  expect(ann:dof("r_elbow_flexion") == 1.0, "pose sets a DOF")
  local a = ann:play(troupe.sequence{ r_knee_flexion = { {0, 0.2}, {1, 0.2} } })
  run(0.01)
  expect(#ann:actions() == 1 and ann:actions()[1] == a, "actions() lists the running one")
end)

test("a wait inside a coroutine the behavior made is an error, not a silent return", function()
  local ann = troupe.actor{ name = "ann" }
  local t0 = troupe.time()
  for _, inner in ipairs({
    function() wait(2.0) end,
    function() ann:play(troupe.sequence{ r_elbow_flexion = { {0, 0}, {1, 1} } }):wait() end,
    function() wait_until(function() return false end, 1) end,
  }) do
    local ok, e = pcall(coroutine.wrap(inner))
    expect(not ok and tostring(e):find("not in a coroutine it made", 1, true), tostring(e))
    -- Called from a Lua line, Lua 5.4's wrap put that line's place before the error's
    -- own: `waits.lua:N: waits.lua:N: …`.
    ok, e = pcall(function() coroutine.wrap(inner)() end)
    local _, places = tostring(e):gsub("waits%.lua:%d+: ", "")
    expect(places == 1, "the place once: " .. tostring(e))
  end
  -- A wrapped coroutine still yields, returns and ends as Lua's does.
  local gen = coroutine.wrap(function(a) local b = coroutine.yield(a + 1); return b * 2 end)
  expect(gen(1) == 2 and gen(5) == 10, "yields and returns")
  local ok, e = pcall(gen)
  expect(not ok and tostring(e):find("cannot resume dead coroutine", 1, true), tostring(e))
  local _, e2 = pcall(coroutine.wrap(function() error({ code = 7 }) end))
  expect(type(e2) == "table" and e2.code == 7, "a table error passes as it is")
  expect(troupe.time() == t0, "no time passed")
  run(0.5)   -- the test's own waits still wait
  expect(troupe.time() > t0, "the test waited")
end)
