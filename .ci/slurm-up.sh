#!/usr/bin/env bash
# Bring up a real single-node Slurm cluster on this machine, for the tests of
# littoral's Slurm batch scripts. Debian 12, run as root, no systemd: installs
# Debian's slurm-wlm and munge (apt-get) if missing, makes a munge key, starts
# munged, writes /etc/slurm/slurm.conf (one node = this host, all its CPUs and
# most of its memory, partition "debug", cons_tres with CR_Core_Memory so
# --mem is honoured, no cgroups, no accounting), starts slurmctld and slurmd
# and waits until the node is idle. Idempotent: a second run only checks.
#
#   .ci/slurm-up.sh          bring the cluster up (or check it is up)
#   .ci/slurm-up.sh --check  also run a job array and a job depending on it
set -euo pipefail

check=0
case "${1:-}" in
  --check) check=1 ;;
  "") ;;
  *) echo "usage: $0 [--check]" >&2; exit 2 ;;
esac

export PATH="$PATH:/usr/local/sbin:/usr/sbin:/sbin"

say() { echo "slurm-up: $*"; }
die() { echo "slurm-up: error: $*" >&2; exit 1; }

host=$(hostname -s)
conf_dir=/etc/slurm
log_dir=/var/log/slurm
ctld_log=$log_dir/slurmctld.log
slurmd_log=$log_dir/slurmd.log
ctld_pid=/run/slurmctld.pid
slurmd_pid=/run/slurmd.pid

show_logs() {
  for f in /var/log/munge/munged.log "$ctld_log" "$slurmd_log"; do
    [[ -f $f ]] || continue
    echo "----- tail $f" >&2
    tail -n 25 "$f" >&2
  done
}

# pid_alive FILE NAME: the pid in FILE runs a process called NAME.
pid_alive() {
  local pid
  [[ -s $1 ]] || return 1
  pid=$(<"$1")
  [[ $pid =~ ^[0-9]+$ ]] && [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$2" ]] &&
    [[ $(awk '{ print $3 }' "/proc/$pid/stat" 2>/dev/null) != Z ]]
}

# stop_daemon PIDFILE NAME: stop the daemon we started (by its pid file).
stop_daemon() {
  local pid i
  pid_alive "$1" "$2" || return 0
  pid=$(<"$1")
  kill "$pid" 2>/dev/null || true
  for ((i = 0; i < 50; i++)); do
    pid_alive "$1" "$2" || return 0
    sleep 0.2
  done
  kill -9 "$pid" 2>/dev/null || true
}

# 1. Packages.
installed() {
  local c
  for c in sbatch slurmctld slurmd munged; do command -v "$c" >/dev/null || return 1; done
}
if installed; then
  say "slurm and munge already installed"
else
  say "installing slurm-wlm and munge (apt-get)"
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -q slurm-wlm munge >/dev/null 2>&1 ||
    { apt-get update -q >/dev/null && apt-get install -y -q slurm-wlm munge >/dev/null; }
fi
installed || die "sbatch, slurmctld, slurmd or munged missing after install"
say "$(slurmd -V)"

# 2. Munge: key, directories, daemon.
getent passwd munge >/dev/null || die "no munge user (the munge package makes it)"
install -d -o munge -g munge -m 0700 /etc/munge /var/lib/munge /var/log/munge
install -d -o munge -g munge -m 0755 /run/munge
if [[ ! -s /etc/munge/munge.key ]]; then
  say "creating munge key"
  if command -v mungekey >/dev/null; then
    mungekey --create --keyfile=/etc/munge/munge.key
  else
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
  fi
fi
chown munge:munge /etc/munge/munge.key
chmod 0400 /etc/munge/munge.key
if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  say "munged already running"
else
  say "starting munged"
  rm -f /run/munge/munge.socket.2.lock
  runuser -u munge -- /usr/sbin/munged
  for ((i = 0; i < 50; i++)); do
    munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
    sleep 0.2
  done
  munge -n | unmunge >/dev/null || { show_logs; die "munge -n | unmunge fails"; }
fi
say "munge ok"

# 3. slurm.conf for this one node.
cpus=$(nproc)
mem_total=$(awk '/^MemTotal:/ { print int($2 / 1024) }' /proc/meminfo)
margin=$((mem_total / 20 > 512 ? mem_total / 20 : 512))
real_mem=$((mem_total - margin))
# Jobs that ask for no --mem get a share per CPU, not the whole node.
def_mem=$((real_mem / cpus))
# Socket/core/thread layout as slurmd sees it, when it agrees with nproc
# (else slurmd logs "Node reconfigured socket/core boundaries").
topo=""
hw=$(slurmd -C 2>/dev/null | head -n 1 || true)
if [[ $hw =~ CPUs=([0-9]+)\ .*SocketsPerBoard=([0-9]+)\ CoresPerSocket=([0-9]+)\ ThreadsPerCore=([0-9]+) ]] &&
  ((BASH_REMATCH[1] == cpus)); then
  topo=" SocketsPerBoard=${BASH_REMATCH[2]} CoresPerSocket=${BASH_REMATCH[3]} ThreadsPerCore=${BASH_REMATCH[4]}"
fi
install -d -m 0755 "$conf_dir" "$log_dir" /var/spool/slurmctld /var/spool/slurmd
conf=$(
  cat <<EOF
# Written by littoral's .ci/slurm-up.sh: a single-node cluster for CI.
ClusterName=littoral-ci
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
# A job whose afterok dependency failed is cancelled, not left pending
# forever (which would hang an sbatch --wait).
DependencyParameters=kill_invalid_depend
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=$def_mem
ReturnToService=2
MailProg=/bin/true
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=$ctld_pid
SlurmdPidFile=$slurmd_pid
SlurmctldLogFile=$ctld_log
SlurmdLogFile=$slurmd_log
SlurmctldDebug=info
SlurmdDebug=info
SlurmdTimeout=60
InactiveLimit=0
MinJobAge=300
KillWait=10
Waittime=0
NodeName=$host NodeAddr=127.0.0.1 NodeHostname=$host CPUs=$cpus$topo RealMemory=$real_mem State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
)
restart=0
if [[ -f $conf_dir/slurm.conf ]] && [[ $(<"$conf_dir/slurm.conf") == "$conf" ]]; then
  say "slurm.conf up to date ($host: $cpus CPUs, ${real_mem} MiB)"
else
  say "writing $conf_dir/slurm.conf ($host: $cpus CPUs, ${real_mem} MiB)"
  printf '%s\n' "$conf" >"$conf_dir/slurm.conf"
  chmod 0644 "$conf_dir/slurm.conf"
  restart=1
fi

# 4. Daemons.
if ((restart)) && { pid_alive "$ctld_pid" slurmctld || pid_alive "$slurmd_pid" slurmd; }; then
  say "config changed: stopping slurmd and slurmctld"
  stop_daemon "$slurmd_pid" slurmd
  stop_daemon "$ctld_pid" slurmctld
fi
if pid_alive "$ctld_pid" slurmctld; then
  say "slurmctld already running"
else
  say "starting slurmctld"
  slurmctld || { show_logs; die "slurmctld did not start"; }
fi
if pid_alive "$slurmd_pid" slurmd; then
  say "slurmd already running"
else
  say "starting slurmd"
  slurmd || { show_logs; die "slurmd did not start"; }
fi

# 5. Wait for the node to be idle (resume it once if down or drained).
say "waiting for node $host to be idle"
state=""
resumed=0
deadline=$((SECONDS + 60))
while ((SECONDS < deadline)); do
  state=$(sinfo -h -N -n "$host" -o %T 2>/dev/null | head -n 1 || true)
  case "$state" in
    idle | mixed | allocated | completing) break ;;
    down* | drain* | fail*)
      if ((!resumed)); then
        say "node $host is $state: resuming it"
        scontrol update nodename="$host" state=resume || true
        resumed=1
      fi
      ;;
  esac
  sleep 0.5
done
case "$state" in
  idle | mixed | allocated | completing) say "node $host is $state" ;;
  *)
    sinfo -N -l >&2 || true
    scontrol show node "$host" >&2 || true
    show_logs
    die "node $host not idle after 60 s (state: ${state:-none})"
    ;;
esac

# 6. Optional self-check: an array job, then a job depending on it.
if ((check)); then
  dir=$(mktemp -d /tmp/slurm-check.XXXXXX)
  say "check: job array 0-2 in $dir"
  array=$(sbatch --parsable --wait --chdir="$dir" --array=0-2 --mem=64M \
    --time=5 --output="$dir/array-%A_%a.out" \
    --wrap 'echo task $SLURM_ARRAY_TASK_ID > probe-$SLURM_ARRAY_TASK_ID.txt') ||
    { show_logs; die "array job failed"; }
  say "check: dependent job after array $array"
  dep=$(sbatch --parsable --wait --chdir="$dir" --dependency="afterok:$array" \
    --mem=64M --time=5 --output="$dir/dep-%j.out" \
    --wrap 'cat probe-0.txt probe-1.txt probe-2.txt > all.txt') ||
    { show_logs; die "dependent job failed"; }
  expected=$'task 0\ntask 1\ntask 2'
  [[ -f $dir/all.txt && $(<"$dir/all.txt") == "$expected" ]] ||
    die "check: unexpected output in $dir/all.txt"
  say "check: ok (array $array, dependent job $dep)"
  rm -rf "$dir"
fi
say "cluster littoral-ci up"
