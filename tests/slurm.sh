#!/usr/bin/env bash
# Real SLURM test (issue 16), run by .ci/run: installs Debian's slurm-wlm and munge, starts a one-node cluster
# (munged, slurmctld, slurmd; configuration and state in a temporary directory through SLURM_CONF, nothing in
# /etc/slurm), submits the script `pedsynth slurm` writes (a 3-task array + a dependent merge job) for a small
# spec, waits, and compares the dataset with a local single run byte for byte. The daemons are stopped by their
# pid files when the script ends, whatever happens.
#
# Usage: bash tests/slurm.sh PEDSYNTH_BINARY   (as root, as CI runs; ../shared/reference/slurm-single-node.md)
set -euo pipefail
pedsynth="$(realpath "$1")"
repo="$(cd "$(dirname "$0")/.." && pwd)"
spec="$repo/tests/data/specs/cluster_small.yaml"
# An override, to check that the script passes it on to every task and to the merge job.
sets=(--set dataset.seed=8)

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

work="$(mktemp -d)"
started_munge=""
cleanup() {
  for pidfile in "$work/slurmd.pid" "$work/slurmctld.pid" $started_munge; do
    if [ -s "$pidfile" ]; then kill "$(cat "$pidfile")" 2>/dev/null || true; fi
  done
  sleep 1
  rm -rf "$work"
}
trap cleanup EXIT

# munge: a key, its directories, the daemon as the munge user (unless one already answers).
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  mkdir -p /etc/munge /run/munge /var/log/munge /var/lib/munge
  if [ ! -s /etc/munge/munge.key ]; then
    head -c 1024 /dev/urandom >/etc/munge/munge.key
  fi
  chown munge:munge /etc/munge/munge.key /run/munge /var/log/munge /var/lib/munge
  chmod 400 /etc/munge/munge.key
  su -s /bin/sh munge -c munged
  started_munge=/run/munge/munged.pid
fi
munge -n | unmunge | grep -q 'STATUS: *Success'

host="$(hostname -s)"
mem_mb=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 1024 ))
mkdir -p "$work/state" "$work/spool"
export SLURM_CONF="$work/slurm.conf"
cat >"$SLURM_CONF" <<EOF
ClusterName=pedsynth-test
SlurmctldHost=$host
SlurmUser=root
AuthType=auth/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
MinJobAge=3600
NodeName=$host CPUs=$(nproc) RealMemory=$mem_mb State=UNKNOWN
PartitionName=main Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld
slurmd
for _ in $(seq 60); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qx idle; then break; fi
  sleep 1
done
sinfo -h -o '%T' | grep -qx idle || { echo "slurm: the node never became idle"; cat "$work"/*.log; exit 1; }

# The script pedsynth writes, submitted as a user would.
cd "$work"
"$pedsynth" slurm "$spec" --out sharded --array 3 --cpus 1 --pedsynth "$pedsynth" --script submit.sh "${sets[@]}"
bash submit.sh | tee submit.log
ids=$(grep -o 'job [0-9]*' submit.log | awk '{print $2}' | tr '\n' ' ')
read -r array_job merge_job <<<"$ids"
for _ in $(seq 900); do
  if [ -z "$(squeue -h -j "$array_job,$merge_job" 2>/dev/null)" ]; then break; fi
  sleep 1
done
state() { scontrol show job "$1" | tr ' ' '\n' | grep '^JobState=' | sort -u | tr '\n' ' '; }
echo "array job $array_job: $(state "$array_job"); merge job $merge_job: $(state "$merge_job")"
for log in sharded.logs/*.log; do echo "== $log"; tail -n 3 "$log"; done
[ "$(state "$array_job")" = "JobState=COMPLETED " ] || { echo "the array did not complete"; exit 1; }
[ "$(state "$merge_job")" = "JobState=COMPLETED " ] || { echo "the merge job did not complete"; exit 1; }
for i in 0 1 2; do
  grep -q "shard $i/3 (from the SLURM array task's environment)" "sharded.logs/shard-$i.log" \
    || { echo "task $i did not take its shard from SLURM"; exit 1; }
done
grep -q ': OK' sharded.logs/merge.log || { echo "the merge job's verify did not pass"; exit 1; }

# A local run of the same spec: every file byte-identical.
"$pedsynth" generate "$spec" --out single --quiet "${sets[@]}" >/dev/null
rm -f sharded/.pedsynth.lock sharded/.pedsynth.manifest.lock single/.pedsynth.lock single/.pedsynth.manifest.lock
diff -r single sharded
files=$(find single -type f | wc -l)
echo "slurm: 3 array tasks + merge job on a real slurmctld; $files files byte-identical to a local run"
