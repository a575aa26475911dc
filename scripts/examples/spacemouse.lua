-- A crate moved and turned with a SpaceMouse (troupe.devices.spacemouse, docs/devices.md).
-- This replays spacemouse.rec (push right 2 s, twist counter-clockwise 1 s, lift 1 s); with
-- a SpaceMouse plugged in, remove `replay` (and give `path = "/dev/hidrawN"` to pick one)
-- and record a session with `troupe run … --record-devices session.rec`.
-- Watch: troupe view scripts/examples/spacemouse.lua

local crate = troupe.object{ name = "crate", shape = "box", size = {0.3, 0.3, 0.3}, at = {0, 1, 0} }
troupe.actor{ name = "ann", at = {0, 0, 1.2}, facing = 180 }

troupe.devices.spacemouse{
  object = crate,
  replay = "spacemouse.rec",
  speed = 0.25,   -- m/s at full deflection
  turn = 90,      -- degrees/s at full deflection
}
