#!/usr/bin/env bash
# Runs docs/scale.md's Slurm array script on a single-node Slurm made from Debian's
# packages, and checks that 3 shards give the files and merged report of one run
# (issue 21). Needs root (it installs slurm-wlm and munge, writes /etc/slurm/slurm.conf
# and starts munged, slurmctld and slurmd, which it stops again at the end).
#
#   bash tools/slurm_local.sh RIGPORT_BIN MANIFEST.jsonl
set -euo pipefail
bin=$(realpath "$1"); manifest=$(realpath "$2")
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
command -v slurmctld > /dev/null || {
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge; }
host=$(hostname -s)
mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm /run/munge
cat > /etc/slurm/slurm.conf <<CONF
ClusterName=rigport
SlurmctldHost=$host
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmUser=root
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
ReturnToService=2
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
[[ -f /etc/munge/munge.key ]] || mungekey -c
chown munge:munge /etc/munge/munge.key /run/munge
pids=()
pgrep -x munged > /dev/null || { su -s /bin/sh munge -c /usr/sbin/munged; pids+=("$(pgrep -x munged)"); }
/usr/sbin/slurmctld -D > /dev/null 2>&1 & pids+=($!)
/usr/sbin/slurmd -D > /dev/null 2>&1 & pids+=($!)
trap 'kill "${pids[@]}" 2> /dev/null || true' EXIT
for _ in $(seq 30); do sinfo -h -o %T 2> /dev/null | grep -q idle && break; sleep 1; done

work=$(mktemp -d); cd "$work"; mkdir logs
cp "$manifest" manifest.jsonl
python3 - "$root/docs/scale.md" <<'PY' > rigport.sbatch
import sys
s = open(sys.argv[1]).read()
a = s.index("```bash\n#!/bin/bash") + len("```bash\n")
print(s[a:s.index("```", a)], end="")
PY
export PATH="$(dirname "$bin"):$PATH"
rigport batch --quiet manifest.jsonl -o one || true
# The documented script as is; the node's size overrides its per-task resources.
sbatch --wait --array=0-2 --cpus-per-task=1 --mem=0 rigport.sbatch || true
diff -r -x '*.jsonl' one out && echo "slurm: files identical to one run"
rigport batch-report --quiet out/.rigport-batch/report-*-of-3.jsonl -o merged.jsonl || true
python3 - <<'PY'
import json
load = lambda p: [dict(json.loads(l), seconds=0) for l in open(p)]
same = load("merged.jsonl") == load("one/.rigport-batch/report-0-of-1.jsonl")
print("slurm: merged report equals one run:", same)
raise SystemExit(0 if same else 1)
PY
