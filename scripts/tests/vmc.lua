-- A VMC performer, replaying the example's stream (scripts/examples/vmc_handover.rec: Pat
-- takes a floating cup, holds it out, opens her hand at about 7.5 s).

local rec = "../examples/vmc_handover.rec"

local function setup()
  local pat = troupe.performer{ name = "pat", devices = { vmc = { replay = rec, hand = "right" } } }
  local bob = troupe.actor{ name = "bob", at = {0, 0, 0.9}, facing = 180 }
  local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.035, height = 0.1, at = {-0.2, 1.0, 0.38} }
  pat:capture{}
  return pat, bob, cup
end

test("the stream's fingers take the cup, and bob takes it from pat", function()
  local pat, bob, cup = setup()
  expect(run_until(function() return cup.holder == pat end, 4), "pat holds the cup")
  local state, object = troupe.devices.hand_state(pat, "right")
  expect(state == "SECURE_GRASP" and object == "cup", state .. " " .. tostring(object))
  local h = troupe.devices.health(pat).vmc
  expect(h.state == "replay" and h.packets > 30 and h.malformed == 0 and h.invalid == 0
         and h.unknown_bones == 0, "health " .. h.state .. " " .. h.packets)
  expect(h.source_time ~= nil and h.source_time > 0, "the sender's time is kept")
  -- Pat is still bringing it forward: Bob takes it once she holds it out.
  run_until(function() return troupe.time() > 2.5 end, 3)
  local rx = bob:receive{ object = cup, from = pat }
  expect(run_until(function() return rx.status == "completed" end, 5), "receive: " .. tostring(rx.error))
  expect(cup.holder == bob, "bob holds the cup")
end)

test("the stream drives the arm and places the root", function()
  local pat = setup()
  local start = pat:joint_position("r_wrist")
  run_until(function() return troupe.time() > 3 end, 4)
  local now = pat:joint_position("r_wrist")
  expect(now[3] - start[3] > 0.2, "the hand came forward: " .. now[3] - start[3])
  -- The root stands where the stream's hips are.
  expect(math.abs(pat:position()[2] - 0.98) < 0.05, "hips height " .. pat:position()[2])
end)

test("vmc options are checked", function()
  local ok, err = pcall(troupe.performer, { name = "x", devices = { vmc = {} } })
  expect(not ok and tostring(err):find("`listen`"), tostring(err))
  ok, err = pcall(troupe.performer, { name = "y", devices = { vmc = { replay = rec, latency = -1 } } })
  expect(not ok and tostring(err):find("latency"), tostring(err))
  ok, err = pcall(troupe.performer, { name = "z", devices = { vmc = { replay = rec, port = 3 } } })
  expect(not ok and tostring(err):find("port"), tostring(err))
  ok, err = pcall(troupe.vmc_out, { to = "127.0.0.1:39539", rate = 0 })
  expect(not ok and tostring(err):find("rate"), tostring(err))
  ok, err = pcall(troupe.vmc_out, { actor = "nobody", to = "127.0.0.1:39539" })
  expect(not ok and tostring(err):find("nobody"), tostring(err))
end)
