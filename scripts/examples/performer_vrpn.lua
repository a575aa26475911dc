-- A performer tracked over VRPN takes a cup from an autonomous actor. Pat's pelvis and
-- wrists are sensors 0, 1 and 2 of a VRPN tracker (`Tracker0`), replayed from
-- performer_vrpn.rec (recorded the way `troupe run --record-devices` records a live
-- server; made by `cargo run -p troupe-drivers --example vrpn_recording`): Pat stands
-- still for the calibration, then holds the right hand out (1.5–3 s) and presses button 0
-- of the wand `Wand0` at 3.5 s. The anatomical converter turns the wrist's position into
-- shoulder and elbow angles. Pat's right hand wears the data glove of
-- performer_handover_glove.rec (closes over 4.5–6 s).
-- Ann picks up the cup and, when Pat presses the button, brings it into Pat's open hand;
-- the glove closes on it and Ann lets go.
-- Live, replace `replay = …` by `device = "Tracker0@tracking-pc", buttons = "Wand0"`.
-- Run: troupe run scripts/examples/performer_vrpn.lua --seconds 12
local ann = troupe.actor{ name = "ann" }
local pat = troupe.performer{ name = "pat", at = {-0.45, 0, 0.8}, facing = 180,
  devices = {
    vrpn = { replay = "performer_vrpn.rec", map = { pelvis = 0, r_wrist = 1, l_wrist = 2 } },
    glove = { replay = "performer_handover_glove.rec", hand = "right" } } }
local cup = troupe.object{ name = "cup", shape = "cylinder", radius = 0.03, height = 0.09,
                           at = {-0.2, 1.05, 0.38} }
pat:capture{}

local asked = false
troupe.devices.on_button("Wand0.0", function(name, down, who)
  if down then
    print(string.format("%.2f s: %s presses %s", troupe.time(), who, name))
    asked = true
  end
end)

ann:behave(function(self)
  self:grasp{ object = cup, hand = "right" }:wait()
  wait_until(function() return asked end)
  local give = self:give{ object = cup, to = pat, timeout = 7 }
  print("give: " .. give:wait() .. (give.error and (" (" .. give.error .. ")") or "")
        .. ", the cup is held by " .. (cup.holder and cup.holder.name or "nobody"))
end)
