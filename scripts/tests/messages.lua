-- One wording for mistakes, each with a test: what was wrong, where, and how to fix it.
local function message(f)
  local ok, err = pcall(f)
  expect(not ok, "the call should fail")
  return err
end

local function says(f, needle)
  local err = message(f)
  expect(err:find(needle, 1, true), "expected `" .. needle .. "` in: " .. err)
  expect(not err:find("runtime error", 1, true), "no mlua prefix: " .. err)
  expect(not err:find("traceback", 1, true), "no traceback in a caught error: " .. err)
  expect(err:find("messages%.lua:%d+: "), "the place of the call: " .. err)
  return err
end

test("a method called with . instead of : says so", function()
  local ann = troupe.actor{ name = "ann" }
  says(function() ann.walk{ to = {1, 0, 0} } end,
    "walk: call it as a method, with `:` (`actor:walk(…)`), not with `.`")
  says(function() ann.on("action_completed", function() end) end,
    "on: call it as a method, with `:` (`actor:on(…)`), not with `.`")
  says(function() ann.position() end, "position: call it as a method, with `:`")
  -- A sequence's method named the actor's: ``(`actor:dofs(…)`)``.
  local s = troupe.sequence{ r_elbow_flexion = { {0, 0}, {1, 1} } }
  says(function() s.dofs() end, "dofs: call it as a method, with `:` (`sequence:dofs(…)`)")
end)

test("a handle's unknown field says where it was asked, and the nearest name", function()
  -- They said `__mlua_index:31: actor has no method or field `mas``: the place of mlua's
  -- lookup code, not the scene's; objects, sequences and handlers answered nil.
  local ann = troupe.actor{ name = "ann" }
  local cup = troupe.object{ name = "cup", shape = "sphere", radius = 0.04, at = {0.3, 1, 0.3} }
  local seq = troupe.sequence{ r_elbow_flexion = { {0, 0}, {1, 1} } }
  local e = says(function() return ann.heigth end, "actor has no method or field `heigth`; did you mean `height`?")
  expect(not e:find("__mlua", 1, true), e)
  says(function() ann:nonexistent() end, "actor has no method or field `nonexistent`")
  says(function() return cup.positon end, "object has no method or field `positon`; did you mean `position`?")
  says(function() return seq.duraton end, "sequence has no method or field `duraton`; did you mean `duration`?")
  says(function() return seq.speed end, "sequence has no method or field `speed` (known: ")
  local a = ann:play(seq)
  says(function() return a.statsu end, "action has no method or field `statsu`; did you mean `status`?")
  local h = ann:on("action_completed", function() end)
  says(function() return h.of end, "handler has no method or field `of`; did you mean `off`?")
  local b = ann:behave(function() end)
  says(function() return b.state end, "behavior has no method or field `state`")
end)

test("an error in a function an action calls is the message alone, with the time", function()
  local ann = troupe.actor{ name = "ann" }
  local e = says(function() ann:walk{ velocity = function(t) error("bad speed") end, duration = 2 } end,
    "walk: `velocity` failed at t = 0.00 s: ")
  expect(e:find("messages%.lua:%d+: bad speed$"), e)
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1, at = {-0.2, 1.05, 0.38} }
  expect(ann:grasp{ object = cup, hand = "right" }:wait() == "completed", "grasped")
  e = says(function()
    ann:manipulate{ object = cup, duration = 1, keys = function(t)
      if t > 0.5 then error("boom") end
      return {-0.2, 1.1, 0.4}
    end }
  end, "manipulate: `keys` failed at t = 0.52 s: ")
  expect(e:find("messages%.lua:%d+: boom$"), e)
end)

test("options inside options are checked, and so are magnitudes no body could take", function()
  local ann = troupe.actor{ name = "ann" }
  says(function() ann:simulate{ duration = 0.5, push = { forc = {0, 1400, 0} } } end,
    "simulate: push: unknown field `forc` (known: force, torque, duration)")
  says(function() ann:simulate{ duration = 0.5, push = { force = {0, 1e300, 0} } } end,
    "push.force must be at most 1e6 N and push.torque at most 1e6 N·m, got 1e300 N and 0e0 N·m")
  says(function() ann:simulate{ small_time_step = 0.1, time_step = 0.01, duration = 1 } end,
    "small_time_step")
  says(function() ann:simulate{ small_time_step = 0.1, time_step = 0.01, duration = 1 } end,
    "at most time_step (0.01 s)")
  says(function() ann:forward_dynamics{ tau = { r_elbow_flexion = 1e308 } } end,
    "forward_dynamics: invalid dynamics: tau[r_elbow_flexion]: 1e308 (a finite number within ±1e9)")
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1, at = {-0.2, 1.05, 0.38} }
  expect(ann:grasp{ object = cup, hand = "right" }:wait() == "completed", "grasped")
  says(function() ann:manipulate{ object = cup, keys = { { t = 1, at = {-0.2, 1.1, 0.4}, rot = {0, 90, 0} } } } end,
    "manipulate: keys[1]: unknown field `rot` (known: t, at, rotation)")
end)

test("names that could not be file names are refused", function()
  -- Each name goes into a recording's file names (`rec.NAME.bvh`): a '/' wrote elsewhere.
  says(function() troupe.actor{ name = "x/../../escaped" } end,
    "an actor's name `x/../../escaped` holds '/': names become file names")
  says(function() troupe.object{ name = "cup\\1", shape = "sphere", radius = 0.1, at = {0, 1, 0} } end,
    "an object's name `cup\\\\1` holds '\\\\'")
  says(function() troupe.actor{ name = "bell\7" } end, "an actor's name `bell\\u{7}` holds '\\u{7}'")
  expect(troupe.actor{ name = "Zoë the 2nd" } ~= nil, "other characters are fine")
end)

test("bad arguments have one wording: what, what it must be, what it got", function()
  local ann = troupe.actor{ name = "ann" }
  says(function() ann:on("action_completed", 5) end,
    "on: the handler must be a function, got integer")
  says(function() ann:on(7, function() end) end, "on: the event must be a string, got integer")
  says(function() ann:behave("go") end, "behave: the argument must be a function, got string")
  says(function() ann:dof({}) end, "dof: argument 1 must be a string, got table")
  says(function() troupe.get_actor(false) end, "get_actor: the name must be a string, got boolean")
end)

test("numbers that are not finite say nan or inf", function()
  says(function() troupe.actor{ name = "n", at = {0 / 0, 0, 0} } end,
    "actor: at.x must be a finite number, got nan")
  says(function() troupe.actor{ name = "i", at = {0, math.huge, 0} } end,
    "actor: at.y must be a finite number, got inf")
  says(function() troupe.actor{ name = "h", height = -math.huge } end,
    "actor: option `height` must be a finite number, got -inf")
end)

test("a missing file lists the paths tried", function()
  local ann = troupe.actor{ name = "ann" }
  local err = says(function() ann:play("nope.trk") end, "play: file `nope.trk` not found; looked for ")
  expect(err:find("beside the scene, [^\n]*scripts/tests/nope%.trk"), "the scene's folder: " .. err)
  says(function() troupe.sequence("nope.bvh") end, "sequence: file `nope.bvh` not found")
end)

test("a missing module lists where require looked", function()
  says(function() require("no_such_module") end,
    "require: module `no_such_module` not found; looked for ")
  says(function() require("no_such_module") end, "in the standard library (gestures)")
end)

test("the standard library is found", function()
  local gestures = require("gestures")
  expect(type(gestures.bow) == "function", "gestures.bow")
end)

test("an inline sequence is named after where it was made", function()
  local s = troupe.sequence{ r_elbow_flexion = { {0, 0}, {1, 1} } }
  expect(s.name:match("^sequence@.*messages%.lua:%d+$"), "placeholder name: " .. s.name)
  local named = troupe.sequence{ name = "lift", r_elbow_flexion = { {0, 0}, {1, 1} } }
  expect(named.name == "lift", "a given name is kept")
end)

test("option types are checked: loop = \"no\" is refused", function()
  says(function() troupe.sequence{ loop = "no", r_elbow_flexion = { {0, 0}, {1, 1} } } end,
    "sequence: option `loop` must be a boolean, got string")
end)

test("unknown names: get_actor and get_object answer nil, every other call raises", function()
  local ann = troupe.actor{ name = "ann" }
  troupe.object{ name = "cup", shape = "sphere", radius = 0.04, at = {0.3, 1, 0.3} }
  expect(troupe.get_actor("nobody") == nil, "get_actor answers nil")
  expect(troupe.get_object("nothing") == nil, "get_object answers nil")
  expect(troupe.get_object("cup") ~= nil, "a known name is found")
  says(function() ann:grasp{ object = "nothing" } end, "grasp: ")
  says(function() ann:give{ object = "cup", to = "nobody" } end, "give: ")
  says(function() ann:look_at{ target = "nobody" } end, "look_at: ")
  says(function() ann:dof("tail_wag") end, "unknown DOF `tail_wag` in skeleton `adult`")
  -- A slip of a name gets the nearest one the skeleton has.
  says(function() ann:dof("r_shoulder_twisting") end, "did you mean `r_shoulder_twist`?")
  says(function() ann:joint_position("r_wirst") end, "unknown joint `r_wirst` in skeleton `adult`; did you mean `r_wrist`?")
  says(function() ann:on("action_exploded", function() end) end, "on: unknown event `action_exploded`")
  -- Each query names itself, as `file:line: method: …` promises (they did not).
  says(function() ann:joint_position("r_wirst") end, "joint_position: unknown joint `r_wirst`")
  says(function() ann:dof("r_elbo") end, "dof: unknown DOF `r_elbo`")
  says(function() ann:dofs("tail") end, "dofs: unknown scope `tail`")
  says(function() ann:pose{ r_elbo = 1 } end, "pose: unknown DOF `r_elbo`")
  local s = troupe.sequence{ r_elbow_flexion = { {0, 0}, {1, 1} } }
  says(function() s:value("l_elbow_flexion", 0.5) end, "value: sequence `")
  says(function() s:interpolation("l_elbow_flexion") end, "interpolation: sequence `")
  -- A track that is no DOF of the actor a sequence is given to: named with the sequence
  -- (an inline one is named after its line); a walk following it ignored it.
  local slip = troupe.sequence{ name = "slip", root_x = { {0, 0}, {1, 1} }, root_z = { {0, 0}, {1, 1} },
    root_yw = { {0, 0}, {1, 1} } }
  says(function() ann:walk{ follow = slip } end,
    "walk: sequence `slip`: unknown DOF `root_yw` in skeleton `adult`; did you mean")
  says(function() ann:play(slip) end, "play: sequence `slip`: unknown DOF `root_yw`")
end)

test("an unknown actor or object name lists the scene's, or gives the nearest", function()
  -- `grasp: unknown object `cpu`` listed nothing, though the doc promises the known
  -- names where the list is short.
  local ann = troupe.actor{ name = "ann" }
  troupe.actor{ name = "bob", at = {1, 0, 0} }
  for _, n in ipairs({ "cup", "plate", "jug" }) do
    troupe.object{ name = n, shape = "sphere", radius = 0.04, at = {0.3, 1, 0.3} }
  end
  says(function() ann:grasp{ object = "cupp" } end, "grasp: unknown object `cupp`; did you mean `cup`?")
  says(function() ann:grasp{ object = "saucer" } end, "grasp: unknown object `saucer` (known: cup, plate, jug)")
  says(function() ann:give{ object = "cup", to = "bobb" } end, "give: unknown actor `bobb`; did you mean `bob`?")
end)

test("a character file not found, caught, is the message alone", function()
  local e = says(function() troupe.actor{ name = "nf", look = "no_such_avatar.vrm" } end,
    "actor: look: file `no_such_avatar.vrm` not found; looked for ")
  expect(not e:find("runtime error", 1, true), e)
end)

test("limits name the limit and the place", function()
  local b = troupe.actor{ name = "loop" }:behave(function() while true do end end)
  local _, err = b:wait()
  expect(err:find("^[^\n]*messages%.lua:%d+: instruction budget exceeded"), err)
end)

test("device options have the same wording and types", function()
  troupe.object{ name = "crate", shape = "box", size = {0.3, 0.3, 0.3}, at = {0, 0.15, 1} }
  says(function() troupe.devices.spacemouse{ object = "crate", speed = "fast" } end,
    "spacemouse: option `speed` must be a number, got string")
  says(function() troupe.devices.spacemouse{ object = "crate", turn = 0 / 0 } end,
    "spacemouse: option `turn` must be a finite number, got nan")
  says(function() troupe.performer{ name = "pat", calibrate = {} } end,
    "performer: option `calibrate` must be a string, got table")
end)

test("the test helpers name themselves and what they got", function()
  local function said(f, ...)
    local ok, e = pcall(f, ...)
    expect(not ok, "refused")
    return tostring(e)
  end
  expect(said(expect, false, { 1, 2 }):find("expectation failed: table: ", 1, true), "a table message is shown")
  expect(said(run, -1):find("run: seconds must be a number >= 0, got -1", 1, true), "run names itself")
  expect(said(run, 0 / 0):find("got nan", 1, true), "nan, on every platform")
  expect(said(run_until, 5):find("run_until: the first argument must be a function, got number", 1, true),
         "run_until names itself")
  expect(said(test, "inner", function() end):find("test() defines a test at the scene's top level", 1, true),
         "a test inside a test would never run")
end)

test("a table raised with error is reported with its place and fields, not its address", function()
  -- They said `table: 0x55…`, with the place only in the traceback.
  local ann = troupe.actor{ name = "ann" }
  local here
  local b = ann:behave(function()
    wait(0.05)
    _, here = pcall(function() error("") end); error({ code = "blocked", msg = "the door is shut" })
  end)
  b:wait()
  local e = ann:behavior_error()
  expect(e:find(here .. '{code = "blocked", msg = "the door is shut"}\nstack traceback:', 1, true) == 1, e)
  expect(not e:find("table: 0x", 1, true), e)
  -- A coroutine the behavior made passes the table on; the place is where it was raised.
  local bob = troupe.actor{ name = "bob", at = {2, 0, 0} }
  b = bob:behave(function()
    wait(0.05)
    coroutine.wrap(function()
      _, here = pcall(function() error("") end); error({ 1, 2, nested = { deep = { deeper = true } } })
    end)()
  end)
  b:wait()
  e = bob:behavior_error()
  expect(e:find(here .. "{1, 2, nested = {deep = {…}}}\n", 1, true) == 1, e)
  -- assert with a table message, and the function an action calls.
  local cy = troupe.actor{ name = "cy", at = {4, 0, 0} }
  b = cy:behave(function() wait(0.05); _, here = pcall(function() error("") end); assert(false, { why = 42.5 }) end)
  b:wait()
  expect(cy:behavior_error():find(here .. "{why = 42.5}\n", 1, true) == 1, cy:behavior_error())
  e = says(function() ann:walk{ velocity = function(t) error({ code = 4 }) end, duration = 2 } end,
    "walk: `velocity` failed at t = 0.00 s: ")
  expect(e:find("messages%.lua:%d+: {code = 4}$"), e)
  -- Caught, the table is the table; a table with __tostring reads as it says.
  local ok, t = pcall(error, { code = 7 })
  expect(not ok and type(t) == "table" and t.code == 7, "pcall gets the table")
  local dan = troupe.actor{ name = "dan", at = {6, 0, 0} }
  b = dan:behave(function()
    wait(0.05)
    error(setmetatable({}, { __tostring = function() return "a door is shut" end }))
  end)
  b:wait()
  expect(dan:behavior_error():find("a door is shut\n", 1, true) == 1, dan:behavior_error())
end)

test("error and assert keep Lua's places: levels, tail calls, no place", function()
  local _, e, here
  _, e = pcall(function() return error("tail") end); _, here = pcall(function() error("") end)
  expect(e == here .. "tail", e)
  local function check(x) if not x then error("the caller's fault", 2) end end
  _, e = pcall(function() check(false) end); _, here = pcall(function() error("") end)
  expect(e == here .. "the caller's fault", e)
  _, e = pcall(error, "no place", 0)
  expect(e == "no place", e)
  _, e = pcall(function() assert(false) end); _, here = pcall(function() error("") end)
  expect(e == here .. "assertion failed!", e)
  _, e = pcall(function() assert(nil, "why") end); _, here = pcall(function() error("") end)
  expect(e == here .. "why", e)
  expect(select("#", assert(1, 2, 3)) == 3, "assert returns its arguments")
  _, e = pcall(function() error("x", "two") end)
  expect(e:find("bad argument #2 to 'error'", 1, true), e)
end)
