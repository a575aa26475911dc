-- For tests/zenoh_cli.rs: a leader runs this scene with a glove served by `troupe relay`,
-- a follower runs it from the leader's replicated inputs, and a third run replays the
-- leader's --record-devices file; all three must compute the same postures bit for bit.
-- Two scripted actors: one uses the scene's random numbers and publishes a behavior
-- message after each reach, the other waits for a cue sent by a tool mid-run.
require("replicated_cast")({ zenoh = "troupe/devices/glove-replicated", hand = "right" }, 0.5, false)
