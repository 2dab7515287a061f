#!/usr/bin/env bash
# A Slurm batch job: one Parallax reconstruction spread over the ranks of an MPI job.
#
#   sbatch examples/slurm_reconstruct.sh /shared/photos /shared/run-1
#
# IMAGES and OUT must be on a filesystem every node sees (the ranks exchange their work through
# OUT/shards/ and OUT/cluster_models/) with POSIX locks and coherent memory maps, as SQLite's
# write-ahead log needs: Lustre, GPFS, BeeGFS, not NFS. One rank per node, each using the node's cores with threads:
# the ranks share out images, pairs and clusters, and the threads work inside each share.
# If the job is stopped (time limit, preemption, a failed node), submit the same script again:
# what the database, the shards and the finished clusters hold is not computed again.
#SBATCH --job-name=parallax
#SBATCH --nodes=4
#SBATCH --ntasks-per-node=1
#SBATCH --cpus-per-task=32
#SBATCH --mem=64G
#SBATCH --time=12:00:00
#SBATCH --output=parallax-%j.log
set -euo pipefail

images="${1:?usage: sbatch slurm_reconstruct.sh IMAGES OUT [parallax reconstruct options]}"
out="${2:?usage: sbatch slurm_reconstruct.sh IMAGES OUT [parallax reconstruct options]}"
shift 2
parallax="${PARALLAX_BINARY:-parallax}"

# srun starts the ranks through Slurm's PMIx plugin (Debian's OpenMPI is built with PMIx) and
# gives each its --cpus-per-task cores; on a cluster without it,
# `mpirun -np "$SLURM_NTASKS" --map-by ppr:1:node --bind-to none` does the same (without
# --bind-to none, mpirun may bind each rank to one core, where its threads would queue).
srun --mpi=pmix "$parallax" reconstruct --images "$images" --output "$out" \
  --threads "${SLURM_CPUS_PER_TASK:-1}" --pairs auto --mapper hierarchical "$@"
