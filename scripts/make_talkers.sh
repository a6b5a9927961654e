#!/usr/bin/env bash
# Two talkers for the regression suite's speech scenes (issue 9): real sentences with
# their natural pauses, synthesised by espeak-ng and resampled to 16 kHz mono 16-bit by
# sox. Hand-run; the WAVs are committed in fixtures/audio/.
#   apt-get install espeak-ng sox
set -euo pipefail
out="$(dirname "$0")/../fixtures/audio"
mkdir -p "$out"
tmp=$(mktemp -d)
espeak-ng -v en-us -s 150 -w "$tmp/a.wav" \
  "The robot stops, listens for a while, and then drives on to the next place."
espeak-ng -v en-gb+f3 -s 140 -w "$tmp/b.wav" \
  "Please bring the blue box to the kitchen. Thank you, that is all for today."
sox "$tmp/a.wav" -r 16000 -c 1 -b 16 "$out/talker_a.wav" trim 0 3.0
sox "$tmp/b.wav" -r 16000 -c 1 -b 16 "$out/talker_b.wav" trim 0 3.0
rm -r "$tmp"
soxi -D "$out/talker_a.wav" "$out/talker_b.wav"
