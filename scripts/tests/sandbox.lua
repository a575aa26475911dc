-- The sandbox's limits hold whatever a behavior does to catch them: each case runs in a
-- behavior the test waits for, and must end `failed` with the limit and its place.
local function fails_with(body, needle)
  local ann = troupe.actor{ name = "ann" }
  local b = ann:behave(body)
  local status, err = b:wait()
  expect(status == "failed", "the behavior fails, got " .. tostring(status))
  expect(err and err:find(needle, 1, true), "error names " .. needle .. ": " .. tostring(err))
  expect(err:find("sandbox.lua:%d+:"), "error has file:line: " .. err)
  return err
end

test("the instruction budget cannot be caught by pcall", function()
  fails_with(function()
    while true do pcall(function() while true do end end) end
  end, "instruction budget exceeded")
end)

test("nor by nested pcall and xpcall", function()
  fails_with(function()
    for _ = 1, 1e9 do
      pcall(pcall, xpcall, function() while true do end end, function(e) return e end)
    end
  end, "instruction budget exceeded")
end)

test("a looping error handler is stopped", function()
  fails_with(function()
    xpcall(function() error("first") end, function() while true do end end)
  end, "instruction budget exceeded")
end)

test("nor by a coroutine", function()
  fails_with(function()
    local co = coroutine.create(function() while true do end end)
    while true do coroutine.resume(co) end
  end, "instruction budget exceeded")
end)

test("a string pattern that would backtrack for ever is refused before it runs", function()
  -- 40 repetitions sharing 40 letters: some 10^22 ways, inside Lua's C matcher, where no
  -- instruction is counted (the tick never ended).
  local ok, e = pcall(string.find, string.rep("a", 40), string.rep("a*", 40) .. "b")
  expect(not ok and tostring(e):find("string.find: the pattern could take over 5e8 steps on a 40-byte string", 1, true),
         tostring(e))
  ok, e = pcall(function() return ("a"):rep(40):gsub(("a*"):rep(40) .. "b", "") end)
  expect(not ok and tostring(e):find("string.gsub: the pattern could take", 1, true), tostring(e))
  -- Whatever follows a balance, and a caret that gmatch takes as a character, count too.
  ok, e = pcall(string.find, "()" .. string.rep("a", 30), "%b()" .. string.rep("a*", 30) .. "b")
  expect(not ok and tostring(e):find("the pattern could take", 1, true), tostring(e))
  ok, e = pcall(function() return string.gmatch("^" .. string.rep("a", 30), "^" .. string.rep("a*", 30) .. "b")() end)
  expect(not ok and tostring(e):find("string.gmatch: the pattern could take", 1, true), tostring(e))
  -- The usual patterns pass, on long strings too.
  local long = string.rep("word ", 20000)
  expect(select(2, long:gsub("%w+", "")) == 20000, "gsub over 100 kB")
  expect(long:match("^%s*(.-)%s*$") == long:sub(1, -2), "trim of 100 kB")
  local t = {}
  for k, v in ("a=1, b=2"):gmatch("(%w+)=(%w+)") do t[#t + 1] = k .. v end
  expect(table.concat(t, ",") == "a1,b2", table.concat(t, ","))
end)

test("passes over long strings count in the instruction budget", function()
  fails_with(function()
    local s = string.rep("a", 1e6)
    for _ = 1, 1000 do s:gsub("a", "b") end   -- 10 s of C work in one resume before
  end, "instruction budget exceeded")
end)

test("a string.rep bomb inside pcall fails the behavior", function()
  fails_with(function()
    local ok = pcall(string.rep, "x", 1 << 30)
    error("pcall returned " .. tostring(ok))
  end, "memory limit exceeded")
end)

test("a table bomb inside pcall fails the behavior", function()
  fails_with(function()
    pcall(function()
      local t = {}
      while true do t[#t + 1] = { 1, 2, 3 } end
    end)
    error("pcall returned")
  end, "memory limit exceeded")
end)

test("the scene goes on after a limit: other behaviors still run", function()
  local bob = troupe.actor{ name = "bob" }
  local ticks = 0
  local counter = bob:behave(function()
    while true do ticks = ticks + 1; wait(0) end
  end)
  fails_with(function() while true do end end, "instruction budget exceeded")
  local before = ticks
  run(0.1)
  expect(ticks > before, "bob's behavior kept running")
  expect(counter.status == "running", "and is still running")
end)

test("errors caught by pcall are clean text", function()
  local ok, err = pcall(troupe.actor, {})
  expect(not ok, "refused")
  expect(err:match("^[^\n]*sandbox%.lua:%d+: actor: `name` is required$"),
    "clean message with its place, got " .. tostring(err))
  local ok2, err2 = pcall(error, "plain", 0)
  expect(not ok2 and err2 == "plain", "Lua errors are unchanged")
end)
