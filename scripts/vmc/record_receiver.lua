-- Listens for Pat's VMC stream (scripts/vmc/record_handover.sh records it with
-- --record-devices); the same performer as scripts/examples/vmc_handover.lua, live.
local pat = troupe.performer{ name = "pat",
  devices = { vmc = { listen = "127.0.0.1:39541", hand = "right" } } }
pat:capture{}
