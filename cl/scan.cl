/* scan.cl — exclusive prefix sum of ints in three launches: each work-group
 * scans its block and records the block's sum; one work-group scans the block
 * sums; the block offsets are added back. Used for cell starts (binning) and
 * neighbour-list offsets (contacts). MC_SCAN_WG is a power of two. */

#include "mc_shim.h"

/* Exclusive scan of `value` over the work-group (Hillis–Steele). */
MC_FN int workgroup_exclusive_scan(__local int* tmp, int value) {
  const int lid = get_local_id(0);
  tmp[lid] = value;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (int offset = 1; offset < MC_SCAN_WG; offset <<= 1) {
    const int add = (lid >= offset) ? tmp[lid - offset] : 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    tmp[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  const int exclusive = tmp[lid] - value;
  barrier(CLK_LOCAL_MEM_FENCE);
  return exclusive;
}

__kernel __attribute__((reqd_work_group_size(MC_SCAN_WG, 1, 1)))
void scan_blocks(__global const int* in, __global int* out,
                 __global int* block_sums, int n) {
  __local int tmp[MC_SCAN_WG];
  const int gid = get_global_id(0);
  const int value = gid < n ? in[gid] : 0;
  const int excl = workgroup_exclusive_scan(tmp, value);
  if (gid < n) out[gid] = excl;
  if (get_local_id(0) == MC_SCAN_WG - 1) block_sums[get_group_id(0)] = excl + value;
}

/* One work-group: each item scans a contiguous chunk of the block sums. */
__kernel __attribute__((reqd_work_group_size(MC_SCAN_WG, 1, 1)))
void scan_block_sums(__global int* block_sums, int n_blocks,
                     __global int* total) {
  __local int tmp[MC_SCAN_WG];
  const int lid = get_local_id(0);
  const int chunk = (n_blocks + MC_SCAN_WG - 1) / MC_SCAN_WG;
  const int begin = min(lid * chunk, n_blocks);
  const int end = min(begin + chunk, n_blocks);
  int sum = 0;
  for (int k = begin; k < end; ++k) sum += block_sums[k];
  const int excl = workgroup_exclusive_scan(tmp, sum);
  int running = excl;
  for (int k = begin; k < end; ++k) {
    const int v = block_sums[k];
    block_sums[k] = running;
    running += v;
  }
  if (lid == MC_SCAN_WG - 1) total[0] = excl + sum;
}

__kernel void scan_add(__global int* out, __global const int* block_sums, int n) {
  const int gid = get_global_id(0);
  if (gid < n) out[gid] += block_sums[gid / MC_SCAN_WG];
}
