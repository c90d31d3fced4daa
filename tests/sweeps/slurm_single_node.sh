# Sourced by the Slurm test: brings up a single-node Slurm (munged, slurmctld, slurmd)
# in the folder $SLURM_DIR, as the current user, without systemd; slurm_down stops
# exactly the daemons it started (by their pids) and removes nothing outside $SLURM_DIR.
# Needs: munged, slurmctld, slurmd, sbatch, sinfo (Debian: munge, slurm-wlm).

slurm_free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1]); s.close()'
}

slurm_up() {
  local cpus node ctl_port d_port user i
  mkdir -p "$SLURM_DIR/munge" "$SLURM_DIR/state" "$SLURM_DIR/spool"
  chmod 711 "$SLURM_DIR" "$SLURM_DIR/munge"
  # munge: a fresh key, its own socket; -F keeps it in the foreground so $! is its pid
  dd if=/dev/urandom of="$SLURM_DIR/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$SLURM_DIR/munge/munge.key"
  munged -F --force --key-file="$SLURM_DIR/munge/munge.key" --socket="$SLURM_DIR/munge/munge.sock" \
    --pid-file="$SLURM_DIR/munge/munged.pid" --log-file="$SLURM_DIR/munge/munged.log" \
    --seed-file="$SLURM_DIR/munge/munged.seed" >"$SLURM_DIR/munge/munged.out" 2>&1 &
  SLURM_MUNGED_PID=$!
  for i in $(seq 50); do [ -S "$SLURM_DIR/munge/munge.sock" ] && break; sleep 0.1; done
  [ -S "$SLURM_DIR/munge/munge.sock" ] || { echo "munged did not start:"; cat "$SLURM_DIR/munge/munged.log"; return 1; }

  cpus=$(nproc)
  node=vlabnode
  ctl_port=$(slurm_free_port)
  d_port=$(slurm_free_port)
  user=$(id -un)
  cat > "$SLURM_DIR/slurm.conf" <<CONF
ClusterName=vlabtest
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctl_port
SlurmdPort=$d_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$SLURM_DIR/munge/munge.sock
CredType=cred/munge
StateSaveLocation=$SLURM_DIR/state
SlurmdSpoolDir=$SLURM_DIR/spool/%n
SlurmctldPidFile=$SLURM_DIR/slurmctld.pid
SlurmdPidFile=$SLURM_DIR/slurmd.pid
SlurmctldLogFile=$SLURM_DIR/slurmctld.log
SlurmdLogFile=$SLURM_DIR/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
MpiDefault=none
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
NodeName=$node NodeHostname=$(hostname) NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=vlab Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF="$SLURM_DIR/slurm.conf"
  slurmctld -D -i -f "$SLURM_CONF" >"$SLURM_DIR/slurmctld.out" 2>&1 &
  SLURM_CTLD_PID=$!
  slurmd -D -N "$node" -f "$SLURM_CONF" >"$SLURM_DIR/slurmd.out" 2>&1 &
  SLURM_D_PID=$!
  # the node is up when sinfo says idle
  for i in $(seq 100); do
    if sinfo -h -N -o '%t' 2>/dev/null | grep -q '^idle'; then return 0; fi
    sleep 0.2
  done
  echo "Slurm did not come up; sinfo: $(sinfo -N 2>&1)"
  tail -n 20 "$SLURM_DIR/slurmctld.log" "$SLURM_DIR/slurmd.log" "$SLURM_DIR/slurmctld.out" "$SLURM_DIR/slurmd.out" 2>&1
  return 1
}

slurm_down() {
  local pid
  for pid in ${SLURM_D_PID:-} ${SLURM_CTLD_PID:-} ${SLURM_MUNGED_PID:-}; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in ${SLURM_D_PID:-} ${SLURM_CTLD_PID:-} ${SLURM_MUNGED_PID:-}; do
    wait "$pid" 2>/dev/null || true
  done
}
