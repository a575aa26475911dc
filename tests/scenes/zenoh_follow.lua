-- For tests/zenoh_cli.rs: a leader and a follower run this scene and must compute the
-- same postures bit for bit: a performer whose glove is replayed from a recording, two
-- scripted actors that use the scene's random numbers, and a remote message that changes
-- what one of them does.
require("replicated_cast")({ replay = "../../scripts/examples/performer_handover_glove.rec", hand = "right" }, 0.8, true)
