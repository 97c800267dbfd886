/* fc_noise.h: counter-based normal deviates (fusion_core/noise.py): the noise at sample k
 * depends only on (seed, stream, k, channel), SplitMix64 hashes and the Box-Muller transform. */
#ifndef FC_NOISE_H
#define FC_NOISE_H

#include <stdint.h>

uint64_t fc_splitmix64(uint64_t x);
uint64_t fc_stream_key(uint64_t seed, uint64_t stream);
/* The standard normals of sample k of a stream (key from fc_stream_key), channels 0..n-1. */
void fc_normals(uint64_t key, uint64_t k, int n, double *out);
/* The same normals for the channels with used[c] != 0 only, 0.0 for the others: a model whose
 * terms are switched off skips the cost of their deviates and keeps every other channel's. */
void fc_normals_used(uint64_t key, uint64_t k, int n, const unsigned char *used, double *out);

#endif /* FC_NOISE_H */
