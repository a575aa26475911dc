-- A hand-over between a synthetic actor and a performer wearing a data glove (thesis 4.7
-- with 4.5), without hardware: the glove is replayed from performer_handover_glove.rec
-- (open, closes over 4.5–6 s, stays closed, opens over 9–10 s).
-- Ann picks up a ball and gives it to Pat: she brings it into Pat's open right hand; the
-- glove closes, the grasping automaton stops each finger on the ball and, once the thumb
-- and a finger hold it (SECURE_GRASP), attaches it; Ann sees Pat holding it, opens her
-- hand and the give completes. Then Ann takes it back with receive{from = pat} while Pat
-- opens the glove. Pat's arm is held out by a keyframed pose standing in for Flock of
-- Birds data. Run: troupe run scripts/examples/performer_handover.lua --seconds 12
-- (capture runs until cancelled, so the scene is never idle).
local ann = troupe.actor{ name = "ann" }
local pat = troupe.performer{ name = "pat", at = {-0.45, 0, 0.8}, facing = 180,
  devices = { glove = { replay = "performer_handover_glove.rec", hand = "right" } } }
local ball = troupe.object{ name = "ball", shape = "sphere", radius = 0.03, at = {-0.2, 1.05, 0.38} }
local hold_out = troupe.sequence{ r_shoulder_flexion = { {0, 0.7}, {12, 0.7} },
                                  r_elbow_flexion = { {0, 0.6}, {12, 0.6} } }
pat:play(hold_out)
pat:capture{}

local last = "FREE_HAND"
pat:behave(function(self)
  while troupe.time() < 11 do
    local state, object = troupe.devices.hand_state(self)
    if state ~= last then
      print(string.format("%.2f s: pat's hand %s%s", troupe.time(), state,
                          object and (" (" .. object .. ")") or ""))
      last = state
    end
    wait(0.01)
  end
end)

ann:behave(function(self)
  self:grasp{ object = ball, hand = "right" }:wait()
  local give = self:give{ object = ball, to = pat, timeout = 6 }
  print("give: " .. give:wait() .. (give.error and (" (" .. give.error .. ")") or "")
        .. ", the ball is held by " .. (ball.holder and ball.holder.name or "nobody"))
  wait(0.5)
  local rx = self:receive{ object = ball, from = pat }
  print("receive: " .. rx:wait() .. (rx.error and (" (" .. rx.error .. ")") or "")
        .. ", the ball is held by " .. (ball.holder and ball.holder.name or "nobody"))
end)
