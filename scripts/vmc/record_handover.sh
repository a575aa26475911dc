#!/usr/bin/env bash
# Re-records scripts/examples/vmc_handover.rec: a troupe run sends Pat's motion
# (handover_source.lua) over VMC in real time to a second troupe run whose performer
# listens on 127.0.0.1:39541 and records the datagrams with their arrival times.
set -euo pipefail
cd "$(dirname "$0")/../.."
troupe=${TROUPE:-target/debug/troupe}
out=scripts/examples/vmc_handover.rec
"$troupe" run scripts/vmc/record_receiver.lua --realtime --seconds 12 --record-devices "$out" &
receiver=$!
sleep 1
"$troupe" run scripts/vmc/handover_source.lua --realtime --seconds 11 --vmc-out 127.0.0.1:39541=pat --vmc-rate 30
wait "$receiver"
echo "recorded $out"
