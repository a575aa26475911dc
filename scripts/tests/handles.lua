-- Behavior handles (`actor:behave` returns one) and event handler handles (`actor:on`).
local function hold(dof, length)
  return troupe.sequence{ name = "hold", [dof] = { {0, 0.5}, {length, 0.5} } }
end

test("a behavior handle tells its status and waits for the end", function()
  local ann = troupe.actor{ name = "ann" }
  local b = ann:behave(function() wait(0.2) end)
  expect(b.status == "running", "running at first")
  expect(b.actor == ann, "knows its actor")
  local status, err = b:wait()
  expect(status == "done" and err == nil, "done, got " .. tostring(status))
  expect(b.status == "done", "the handle says done")
end)

test("stop ends a behavior; the others of the actor go on", function()
  local ann = troupe.actor{ name = "ann" }
  local steps = 0
  local looping = ann:behave(function() while true do steps = steps + 1; wait(0.05) end end)
  local other = ann:behave(function() wait(0.5) end)
  run(0.2)
  looping:stop()
  local seen = steps
  run(0.2)
  expect(steps == seen, "a stopped behavior is not resumed")
  expect(looping.status == "stopped", "status stopped, got " .. looping.status)
  expect(other.status == "running", "the other behavior still runs")
  expect(ann:behavior_status() == "running", "the actor is running while one runs")
  expect(other:wait() == "done", "then done")
end)

test("a failed behavior's error is on its handle, and behavior_status waits for the rest",
  function()
    local ann = troupe.actor{ name = "ann" }
    local bad = ann:behave(function() wait(0.1); error("boom") end)
    local good = ann:behave(function() wait(0.4) end)
    local status, err = bad:wait()
    expect(status == "failed", "failed")
    expect(err:find("handles.lua:%d+: boom"), "error with its place: " .. err)
    expect(bad.error == err, "the handle keeps the error")
    expect(ann:behavior_status() == "running", "another behavior still runs")
    good:wait()
    expect(ann:behavior_status() == "failed", "failed once all ended")
  end)

test("a behavior can wait for another", function()
  local ann = troupe.actor{ name = "ann" }
  local first = ann:behave(function() wait(0.3) end)
  local order = {}
  local second = ann:behave(function()
    order[#order + 1] = first:wait()
    order[#order + 1] = troupe.time()
  end)
  second:wait()
  expect(order[1] == "done", "saw the first one end")
  expect(order[2] >= 0.3, "after it ended")
end)

test("on returns a handle whose off removes the handler", function()
  local ann = troupe.actor{ name = "ann" }
  local calls = 0
  local h = ann:on("action_completed", function() calls = calls + 1 end)
  ann:play(hold("r_elbow_flexion", 0.1)):wait()
  run(0.05)
  expect(calls == 1, "called once, got " .. calls)
  expect(h:off() == true, "off says it removed the handler")
  expect(h:off() == false, "a second off removes nothing")
  ann:play(hold("l_elbow_flexion", 0.1)):wait()
  run(0.05)
  expect(calls == 1, "not called after off")
end)

test("a behavior that stops itself ends at its next wait", function()
  local ann = troupe.actor{ name = "ann" }
  local after = false
  local me
  me = ann:behave(function()
    me:stop()
    wait(0.1)
    after = true
  end)
  expect(me:wait() == "stopped", "stopped")
  run(0.2)
  expect(not after, "not resumed after its wait")
end)

test("a behavior cannot wait for itself", function()
  local ann = troupe.actor{ name = "ann" }
  local me
  me = ann:behave(function() me:wait() end)
  local status, err = me:wait()
  expect(status == "failed" and err:find("cannot wait for itself", 1, true), tostring(err))
end)
