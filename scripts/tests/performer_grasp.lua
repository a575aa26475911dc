-- A performer's glove hand through the grasping automaton (thesis 4.7): hand-overs with a
-- synthetic actor, replaying the example's glove recording (open, closes over 4.5–6 s,
-- stays closed, opens over 9–10 s).

local rec = "../examples/performer_handover_glove.rec"

local function setup()
  local ann = troupe.actor{ name = "ann" }
  local pat = troupe.performer{ name = "pat", at = {-0.45, 0, 0.8}, facing = 180,
    devices = { glove = { replay = rec, hand = "right" } } }
  local ball = troupe.object{ name = "ball", shape = "sphere", radius = 0.03, at = {-0.2, 1.05, 0.38} }
  pat:play(troupe.sequence{ r_shoulder_flexion = { {0, 0.7}, {12, 0.7} },
                            r_elbow_flexion = { {0, 0.6}, {12, 0.6} } })
  pat:capture{}
  return ann, pat, ball
end

test("ann gives a ball to pat's glove hand, then takes it back while pat opens", function()
  local ann, pat, ball = setup()
  expect(troupe.devices.hand_state(pat) == "FREE_HAND", "the glove hand starts free")
  local g = ann:grasp{ object = ball, hand = "right" }
  expect(run_until(function() return g.status == "completed" end, 4), "grasp: " .. tostring(g.error))
  local give = ann:give{ object = ball, to = pat, timeout = 6 }
  expect(#pat:actions() == 2, "no receive action is started on a performer")
  local seen = {}
  expect(run_until(function()
    local s = troupe.devices.hand_state(pat)
    if seen[#seen] ~= s then seen[#seen + 1] = s end
    return give.status ~= "active" and give.status ~= "pending"
  end, 8), "the give ended")
  expect(give.status == "completed", "give " .. give.status .. " " .. tostring(give.error))
  expect(ball.holder == pat, "pat holds the ball")
  local state, object = troupe.devices.hand_state(pat, "right")
  expect(state == "SECURE_GRASP" and object == "ball", state .. " " .. tostring(object))
  expect(table.concat(seen, ",") == "FREE_HAND,GRASPING_IN_PROGRESS,SECURE_GRASP",
         table.concat(seen, ","))
  local rx = ann:receive{ object = ball, from = pat }
  expect(run_until(function() return rx.status == "completed" end, 3), "receive: " .. tostring(rx.error))
  expect(ball.holder == ann, "ann took it back")
  expect(run_until(function() return troupe.devices.hand_state(pat) == "FREE_HAND" end, 5),
         "the hand frees when the glove opens")
  expect(ball.holder == ann, "ann still holds it")
end)

test("hand_state and give name bad uses", function()
  local ann, pat, ball = setup()
  local plain = troupe.performer{ name = "plain", at = {1, 0, 0} }
  local ok, e = pcall(troupe.devices.hand_state, plain)
  expect(not ok and tostring(e):find("has no glove") ~= nil, tostring(e))
  ok, e = pcall(troupe.devices.hand_state, pat, "left")
  expect(not ok and tostring(e):find("right hand, not the left") ~= nil, tostring(e))
  ok, e = pcall(function() return pat:give{ object = ball, to = ann } end)
  expect(not ok and tostring(e):find("receiver:receive") ~= nil, tostring(e))
  ok, e = pcall(function() return ann:give{ object = ball, to = pat, timeout = -1 } end)
  expect(not ok and tostring(e):find("timeout") ~= nil, tostring(e))
end)
