-- A performer tracked over VRPN, replaying the example's recording (a tracker Tracker0 with
-- the pelvis and both wrists as sensors 0–2, and the wand Wand0 whose button 0 is down
-- from 3.5 to 3.7 s and whose trigger, analog channel 0, rises from 0 to 1 over 3–3.5 s;
-- see scripts/examples/performer_vrpn.lua).

local rec = "../examples/performer_vrpn.rec"
local map = { pelvis = 0, r_wrist = 1, l_wrist = 2 }

test("the tracked wrist raises the performer's arm through the converter", function()
  local pat = troupe.performer{ name = "pat", at = {-0.45, 0, 0.8}, facing = 180,
    devices = { vrpn = { replay = rec, map = map } } }
  pat:capture{}
  run(1.0)
  expect(troupe.devices.is_calibrated(pat), "calibrated on the first reports")
  local low = pat:joint_position("r_wrist")
  local elbow0 = pat:dof("r_elbow_flexion")
  run(2.5)
  local high = pat:joint_position("r_wrist")
  expect(high[2] - low[2] > 0.2, "the wrist rose: " .. low[2] .. " → " .. high[2])
  expect(pat:dof("r_elbow_flexion") - elbow0 > 0.3, "the elbow bent by IK: " .. pat:dof("r_elbow_flexion"))
  expect(troupe.devices.health(pat).vrpn.state == "replay", "a replay has no connection")
end)

test("units and axes: the same stream read in millimetres or as Z up moves the wrist otherwise", function()
  local function rise(opts)
    local name = "p" .. tostring(opts.units) .. tostring(opts.axes)
    local vrpn = { replay = rec, map = map, units = opts.units, axes = opts.axes }
    local p = troupe.performer{ name = name, at = {-0.45, 0, 0.8}, facing = 180, devices = { vrpn = vrpn } }
    local cap = p:capture{}
    run(1.0)
    local low = p:joint_position("r_wrist")
    run(2.5)
    local high = p:joint_position("r_wrist")
    cap:cancel()
    return high[2] - low[2], high[3] - low[3]
  end
  local up = rise{}
  local up_mm = rise{ units = "mm" }
  local up_z, forward_z = rise{ axes = "z-up" }
  expect(up > 0.2, "metres: the wrist rises " .. up)
  -- (In millimetres the positions shrink to nothing; what is left is the wrist sensor's
  -- turn swinging its lever.)
  expect(math.abs(up_mm) < up / 5, "millimetres: the same numbers barely move it: " .. up_mm)
  expect(up_z < up / 2, "Z up: the data's up is the scene's -Z, not up: " .. up_z)
  expect(math.abs(forward_z) > 0.1, "and the wrist moves along Z: " .. forward_z)
end)

test("buttons are values and events, matched by name patterns", function()
  local pat = troupe.performer{ name = "pat", devices = { vrpn = { replay = rec, map = map } } }
  local events = {}
  troupe.devices.on_button("Wand0.*", function(name, down, who)
    events[#events + 1] = string.format("%.2f %s %s %s", troupe.time(), who, name, tostring(down))
  end)
  troupe.devices.on_button("Other.*", function() error("not this device") end)
  local every = 0
  troupe.devices.on_button(nil, function() every = every + 1 end)   -- nil: every button
  run(3.0)
  expect(next(troupe.devices.buttons()) == nil, "no button reported yet")
  run(0.6)
  expect(troupe.devices.buttons("Wand0.*")["Wand0.0"] == true, "button 0 down at 3.6 s")
  expect(troupe.devices.buttons("Nothing*")["Wand0.0"] == nil, "the pattern filters")
  run(0.5)
  expect(troupe.devices.buttons()["Wand0.0"] == false, "and up again")
  expect(#events == 2, "two events: " .. table.concat(events, "; "))
  expect(every == 2, "a nil pattern saw " .. every .. " button events")
  expect(events[1]:find("pat Wand0.0 true") ~= nil, events[1])
  expect(events[2]:find("pat Wand0.0 false") ~= nil, events[2])
end)

test("analog channels are values and events", function()
  local pat = troupe.performer{ name = "pat", devices = { vrpn = { replay = rec, map = map } } }
  local seen = {}
  troupe.devices.on_analog("Wand0.0", function(name, value, who)
    seen[#seen + 1] = value
    expect(name == "Wand0.0" and who == "pat", name .. " " .. who)
  end)
  run(2.8)
  expect(next(troupe.devices.analogs()) == nil, "no channel reported yet")
  run(1.0)
  expect(troupe.devices.analogs("Wand0.*")["Wand0.0"] == 1, "the trigger is fully pulled: " .. tostring(troupe.devices.analogs()["Wand0.0"]))
  expect(#seen >= 4, "an event per change: " .. #seen)
  for i = 2, #seen do expect(seen[i] > seen[i - 1], "rising: " .. table.concat(seen, " ")) end
  expect(seen[1] == 0, "from 0: " .. seen[1])
end)

test("bad VRPN options are clear errors", function()
  -- Each case its own name: troupe.performer makes the actor before reading the devices.
  for i, case in ipairs{
    { { map = map }, "`device`" },
    { { device = "Tracker0", map = map }, "no '@'" },
    { { device = "T@host:99999", map = map }, "not a number" },
    { { replay = rec }, "`map`" },
    { { replay = rec, map = { nose = 0 } }, "no joint 'nose'" },
    { { replay = rec, map = { pelvis = -1 } }, "not a sensor" },
    { { replay = rec, map = map, units = "inch" }, "units must be" },
    { { replay = rec, map = map, axes = "x-up" }, "axes must be" },
    { { replay = rec, map = map, device = "T@h" }, "not both" },
    { { replay = rec, map = map, colour = 1 }, "unknown option `colour`" },
  } do
    local ok, e = pcall(troupe.performer, { name = "bad" .. i, devices = { vrpn = case[1] } })
    expect(not ok and tostring(e):find(case[2], 1, true) ~= nil, case[2] .. ": " .. tostring(e))
  end
  local ok, e = pcall(troupe.performer, { name = "both", devices = {
    osc = { listen = "127.0.0.1:0", joints = { "pelvis" } }, vrpn = { replay = rec, map = map } } })
  expect(not ok and tostring(e):find("one source of body poses", 1, true) ~= nil, tostring(e))
end)
