#!/bin/bash
# CPU-time A/B of two builds of driver.cpp (./driver_base, ./driver_new), alternated 3 rounds
# per set: ab.sh "dist 3 near" "inter 1 touching" ...  (REPS=3 by default)
for s in "$@"; do
  set -- $s
  for round in 1 2 3; do
    for b in base new; do
      echo "$b $1 $2 $3 $(REPS=${REPS:-3} ./driver_$b $1 $2 $3 2>&1 >/dev/null | awk '{print $2}')"
    done
  done
done
