-- troupe's Lua prelude: the waiting functions, written over coroutine.yield. The Rust
-- director reads what a behavior yields and resumes it when the condition holds.
local yield, isyieldable = coroutine.yield, coroutine.isyieldable
local type, error, select = type, error, select

-- The sandbox's limits cannot be caught: once a resume hits one, every pcall, xpcall,
-- coroutine.resume and coroutine.close that catches an error raises the limit's message
-- again instead of returning. Errors they do return are clean text (no "runtime error:"
-- prefix, no traceback). `limit(err)` gives the limit's message, or nil and the clean error.
local limit = __troupe_limit
local raw_pcall, raw_xpcall = pcall, xpcall
local raw_resume, raw_close = coroutine.resume, coroutine.close

local function caught(ok, ...)
  if ok then return ok, ... end
  local stop, clean = limit((...))
  if stop then error(stop, 0) end
  return false, clean, select(2, ...)
end

function pcall(f, ...)
  return caught(raw_pcall(f, ...))
end

function xpcall(f, handler, ...)
  return caught(raw_xpcall(f, function(e)
    local stop, clean = limit(e)
    if stop then return e end
    return handler(clean)
  end, ...))
end

coroutine.resume = function(co, ...)
  return caught(raw_resume(co, ...))
end

coroutine.close = function(co)
  return caught(raw_close(co))
end

-- Lua 5.4's coroutine.wrap puts the place of the call that resumed it before a string
-- error raised inside, which names its own place already: `s.lua:22: s.lua:22: wait() …`.
-- This one passes the error on as it was raised (as Lua 5.3 did).
local status = coroutine.status
coroutine.wrap = function(f)
  local co = coroutine.create(f)
  local function pass(ok, ...)
    if ok then return ... end
    if status(co) == "dead" then raw_close(co) end
    error((...), 0)
  end
  return function(...)
    if status(co) == "dead" then error("cannot resume dead coroutine", 2) end
    return pass(coroutine.resume(co, ...))
  end
end

-- The coroutines of behaviors and tests (the director's), weakly: a coroutine a behavior
-- makes itself would take the director's requests to wait as its own values.
local running = coroutine.running
local own = setmetatable({}, { __mode = "k" })
__troupe_own_thread = function(co) own[co] = true end

local function must_yield(name)
  if not isyieldable() then
    error(name .. "() can only be called inside a behavior or a test", 3)
  end
  if not own[running()] then
    error(name .. "() waits only in a behavior or a test itself, not in a coroutine it made: "
      .. "call it there", 3)
  end
end

-- `seconds` for `name` (none: 0), or the error of its caller's caller.
local function duration(name, seconds)
  seconds = seconds or 0
  if type(seconds) ~= "number" or seconds < 0 or seconds ~= seconds then
    local got = seconds ~= seconds and "nan" or tostring(seconds)
    error(name .. ": seconds must be a number >= 0, got " .. got, 3)
  end
  return seconds
end

---@async
function wait(seconds)
  must_yield("wait")
  return yield("time", duration("wait", seconds))
end

---@async
function wait_until(fn, timeout)
  must_yield("wait_until")
  if type(fn) ~= "function" then
    error("wait_until: the first argument must be a function, got " .. type(fn), 2)
  end
  if timeout ~= nil and (type(timeout) ~= "number" or timeout < 0) then
    error("wait_until: timeout must be a number >= 0 or nil, got " .. tostring(timeout), 2)
  end
  return yield("until", fn, timeout)
end

local is_action = __troupe_is_action
local value_name = __troupe_value_name

-- The actions given to `name` (as arguments or in one list), each checked here so that
-- the error names the argument and the caller's place, and pcall can catch it.
local function handles(name, ...)
  local list, n = { ... }, select("#", ...)
  if n == 1 and type(list[1]) == "table" and not is_action(list[1]) then
    list = list[1]
    n = #list
  end
  if n == 0 then error(name .. ": give at least one action", 3) end
  -- By count, not ipairs: a nil among the arguments is refused, not the end of them.
  for i = 1, n do
    if not is_action(list[i]) then
      error(string.format("%s: argument %d must be an action, got %s", name, i, value_name(list[i])), 3)
    end
  end
  return list
end

---@async
function wait_all(...)
  must_yield("wait_all")
  return yield("all", handles("wait_all", ...))
end

---@async
function wait_any(...)
  must_yield("wait_any")
  return yield("any", handles("wait_any", ...))
end

-- Scenario tests: run() and run_until() advance the simulation from inside a test.
---@async
function run(seconds)
  must_yield("run")
  return yield("time", duration("run", seconds))
end

---@async
function run_until(fn, timeout)
  must_yield("run_until")
  if type(fn) ~= "function" then
    error("run_until: the first argument must be a function, got " .. type(fn), 2)
  end
  if timeout ~= nil and (type(timeout) ~= "number" or timeout < 0 or timeout ~= timeout) then
    error("run_until: timeout must be a number >= 0 or nil, got " .. tostring(timeout), 2)
  end
  return yield("until", fn, timeout)
end

function expect(cond, message)
  if not cond then
    error("expectation failed: " .. (message == nil and "(no message)" or tostring(message)), 2)
  end
  return cond
end

-- Tests are defined at the scene's top level: one defined inside a test or a behavior
-- would never run.
local define_test = test
function test(name, fn, opts)
  if own[running()] then
    error("test() defines a test at the scene's top level, not inside a test or a behavior", 2)
  end
  return define_test(name, fn, opts)
end

-- The method `action:wait()`; the director returns the action's final status.
---@async
__troupe_action_wait = function(self)
  must_yield("wait")
  return yield("action", self)
end

-- The method `behavior:wait()`; the director returns the behavior's final status
-- ("done", "failed" or "stopped") and its error.
---@async
__troupe_behavior_wait = function(self)
  must_yield("wait")
  return yield("behavior", self)
end
