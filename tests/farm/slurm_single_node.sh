#!/usr/bin/env bash
# Issue #31: a real single-node Slurm cluster inside the test. munged, slurmctld and slurmd run on this
# host from a configuration in a temporary directory (own ports, sockets and spool; nothing system-wide
# is touched). `pteryla farm slurm` submits a job array over moult.json and the dependent assembly; the
# assembled frames must equal `pteryla frames` run in one process, byte for byte. Then one task of a
# second submission is cancelled, the assembly is cancelled with it (afterok), and resubmitting completes
# the sequence.
# Exit 77 (ctest: skipped) with the reason when Slurm or munge is not installed
# (`tools/bootstrap.sh --slurm` installs them) or the daemons cannot start here.
# Usage: slurm_single_node.sh PTERYLA_EXE DATA_DIR WORK_DIR
set -uo pipefail
EXE=$1 DATA=$2 WORK=$3
skip() { echo "SKIP: $*"; exit 77; }
fail() { echo "FAIL: $*"; for f in "$T"/*.log; do echo "== $f"; tail -n 20 "$f"; done; exit 1; }
for tool in munged slurmctld slurmd sbatch squeue sinfo scancel scontrol; do
  command -v "$tool" >/dev/null || PATH=$PATH:/usr/sbin command -v "$tool" >/dev/null ||
    skip "$tool not installed (install Slurm with tools/bootstrap.sh --slurm)"
done
export PATH=$PATH:/usr/sbin
[ "$(id -u)" -eq 0 ] || skip "needs root to run slurmd (it starts job steps as the submitting user)"

T=$(mktemp -d "${TMPDIR:-/tmp}/pteryla-slurm.XXXXXX")
PIDS=()
cleanup() {  # stops only the daemons this script started (by their pid files), then waits for them
  [ -n "${SLURM_CONF:-}" ] && scontrol shutdown >/dev/null 2>&1
  for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null; done
  for _ in $(seq 20); do
    alive=0
    for p in "${PIDS[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break
    sleep 0.25
  done
  for p in "${PIDS[@]}"; do kill -9 "$p" 2>/dev/null; done
  rm -rf "$T"
}
trap cleanup EXIT
mkdir -p "$T/spool" "$T/state" "$T/munge"
HOST=$(hostname -s)
# Ports above the usual 6817/6818, chosen per process so parallel runs do not collide.
PORT=$((20000 + ($$ % 20000)))

# munge with its own key and socket.
dd if=/dev/urandom of="$T/munge/munge.key" bs=1024 count=1 status=none
chmod 700 "$T/munge"; chmod 400 "$T/munge/munge.key"
munged --force --key-file="$T/munge/munge.key" --socket="$T/munge/munge.sock" \
  --pid-file="$T/munge/munged.pid" --log-file="$T/munged.log" --seed-file="$T/munge/seed" ||
  skip "munged does not start here ($(tail -n 1 "$T/munged.log" 2>/dev/null))"
PIDS+=("$(cat "$T/munge/munged.pid")")

CPUS=$(nproc)
cat > "$T/slurm.conf" <<CONF
ClusterName=pteryla-test
SlurmctldHost=$HOST
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$T/munge/munge.sock
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
KillWait=2
NodeName=$HOST CPUs=$CPUS State=UNKNOWN
PartitionName=test Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$T/slurm.conf
slurmctld -i -c || skip "slurmctld does not start here: $(tail -n 2 "$T/slurmctld.log" 2>/dev/null)"
sleep 1
[ -f "$T/slurmctld.pid" ] && PIDS+=("$(cat "$T/slurmctld.pid")")
# A chroot or container without /sys (no cgroup file system, no CPU topology) stops slurmd 22.05 at its
# cgroup plugin ("Unable to initialize cgroup plugin"), though this configuration uses no cgroups; say so.
# (Pointing CgroupPlugin=cgroup/v1 at an empty directory gets slurmd up there, and the test then passes
# on a host with /sys hidden by a private tmpfs; but in the fresh-machine chroot the job array then did
# not finish within ctest's 600 s, so the test skips instead of hanging.)
NOSYS=""
[ -z "$(ls -A /sys/fs/cgroup 2>/dev/null)" ] && NOSYS=" (no cgroup file system: /sys/fs/cgroup is empty or missing here)"
slurmd -N "$HOST" || skip "slurmd does not start here$NOSYS: $(tail -n 2 "$T/slurmd.log" 2>/dev/null)"
sleep 1
[ -f "$T/slurmd.pid" ] && PIDS+=("$(cat "$T/slurmd.pid")")
for _ in $(seq 60); do
  state=$(sinfo -h -n "$HOST" -o %T 2>/dev/null)
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "$state" = idle ] || skip "the Slurm node did not come up (state '$state'): $(tail -n 3 "$T/slurmd.log")"
echo "single-node Slurm up on $HOST (port $PORT, $CPUS CPUs)"

# The reference: one process.
RANGE=(--from 0 --to 6 --fps 1 --lod 0.1 --size 48x48)
SCENE=$DATA/scenes/moult.json
rm -rf "$WORK" && mkdir -p "$WORK"
"$EXE" -q frames "$SCENE" "${RANGE[@]}" -o "$WORK/reference" || fail "reference frames"

wait_jobs() {  # until the queue is empty (at most $1 seconds)
  for _ in $(seq $(($1 * 2))); do
    [ -z "$(squeue -h 2>/dev/null)" ] && return 0
    sleep 0.5
  done
  squeue; return 1
}

OUT=$WORK/farm
ids=$("$EXE" -q farm slurm "$SCENE" "${RANGE[@]}" --chunk 3 -o "$OUT") || fail "farm slurm: $ids"
echo "submitted: $ids"
wait_jobs 120 || fail "jobs did not finish"
[ -f "$OUT/frames.json" ] || fail "no manifest: assembly did not run ($(cat "$OUT"/slurm/assemble_*.log 2>/dev/null))"
[ -f "$OUT/contact_sheet.png" ] || fail "no contact sheet"
for k in 0 1 2 3 4 5 6; do
  f=$(printf 'frame_%04d.png' "$k")
  cmp -s "$OUT/$f" "$WORK/reference/$f" || fail "$f differs from the single-process frame"
done
echo "job array output equals the single-process frames"

# Kill one task: chunk 1's frames are removed so it has work; the partition is down while submitting, so
# no task can start (and finish) before task 1 is cancelled.
OUT2=$WORK/farm_kill
cp -r "$OUT" "$OUT2" && rm -f "$OUT2"/frames.json "$OUT2"/frame_0003.png* "$OUT2"/frame_0004.png*
scontrol update PartitionName=test State=DOWN || fail "scontrol"
ids=$("$EXE" -q farm slurm "$SCENE" "${RANGE[@]}" --chunk 3 -o "$OUT2") || fail "farm slurm (2): $ids"
array=$(sed -n 's/.*"array_job": \([0-9]*\).*/\1/p' <<<"$ids")
scancel "${array}_1" || fail "scancel"
scontrol update PartitionName=test State=UP || fail "scontrol"
wait_jobs 120 || fail "jobs did not finish (2)"
[ -f "$OUT2/frames.json" ] && fail "the assembly ran although a task was cancelled"
"$EXE" -q frames "$SCENE" "${RANGE[@]}" -o "$OUT2" --assemble 2>/dev/null && fail "--assemble passed with missing frames"
ids=$("$EXE" -q farm slurm "$SCENE" "${RANGE[@]}" --chunk 3 -o "$OUT2") || fail "farm slurm (3): $ids"
wait_jobs 120 || fail "jobs did not finish (3)"
[ -f "$OUT2/frames.json" ] || fail "resubmission did not complete the sequence"
for k in 0 1 2 3 4 5 6; do
  f=$(printf 'frame_%04d.png' "$k")
  cmp -s "$OUT2/$f" "$WORK/reference/$f" || fail "$f differs after resubmission"
done
echo "a cancelled task was redone by resubmitting; the sequence is complete and identical"
echo PASS
