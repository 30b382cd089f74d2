#!/bin/sh
# A merged energy table (contention.csv, latency-hiding.csv) with the figures
# the study reads added as columns, each in millijoules a frame: the chip's
# dynamic energy (L1s, L2, cores: chip_dynamic) and leakage (chip_leakage); the
# DRAM's traffic energy (activates with their precharges, read and write bursts:
# dram_traffic) and its energy of time (active and precharge standby, refresh:
# dram_background); and dram_share, the DRAM's fraction of energy_j. Quoted
# values lose their quotes and their commas become + (unquote.awk), so that
# awk -F, reads the result. Used by summary.sh and plot.sh.
#   usage: sh results/energy/derive.sh TABLE.csv > DERIVED.csv
set -eu
awk -f "$(dirname "$0")/../contention/scheduling/unquote.awk" "$1" | awk -F, -v OFS=, -v OFMT=%.9g '
NR == 1 {
  for (i = 1; i <= NF; i++) c[$i] = i
  print $0, "chip_dynamic", "chip_leakage", "dram_traffic", "dram_background", "dram_share"
  next
}
function v(name) { if (!(name in c)) { print "derive.sh: no column " name > "/dev/stderr"; exit 2 } return $c[name] }
{
  cd = v("chip_energy_l1_dynamic_j") + v("chip_energy_l2_dynamic_j") + v("chip_energy_cores_dynamic_j")
  cl = v("chip_energy_l1_leakage_j") + v("chip_energy_l2_leakage_j") + v("chip_energy_cores_leakage_j")
  dt = v("dram_energy_activate_j") + v("dram_energy_read_j") + v("dram_energy_write_j")
  db = v("dram_energy_active_standby_j") + v("dram_energy_precharge_standby_j") + v("dram_energy_refresh_j")
  print $0, cd * 1e3, cl * 1e3, dt * 1e3, db * 1e3, v("dram_energy_j") / v("energy_j")
}'
