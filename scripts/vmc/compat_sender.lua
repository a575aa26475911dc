-- What scripts/vmc/compat.py receives over VMC: Ann walks two metres (the hips bob up and
-- down, so their height is worth comparing with troupe's own recording).
local ann = troupe.actor{ name = "ann" }
ann:walk{ to = {0, 0, 2} }
