"""Counter-based normal deviates: the noise at sample k depends only on (seed, stream, k, channel).

A sequential generator (numpy's PCG64) ties each draw to every draw before it: the noise of
sample k changes when the steps are partitioned differently, when a state is saved and restored
through a format that does not carry the generator, or when another language draws it. Here a
deviate is a pure function of its coordinates instead: SplitMix64 (Steele, Lea, Flood, "Fast
splittable pseudorandom number generators", OOPSLA 2014; the finaliser of Java's SplittableRandom)
hashes (seed, stream, k, draw) to 64 random bits, two of which make one standard normal by the
Box-Muller transform. fusion_core/native/fc_noise.c computes the same function in C: the same
bits, and the same normals but for the last bit of libm's log and cos against numpy's.

    u(seed, stream, k, d) = splitmix64(splitmix64(splitmix64(seed ^ splitmix64(stream)) ^ k) ^ d)
    U = ((u >> 11) + 0.5) / 2^53                                  (in (0, 1), never 0)
    normal(seed, stream, k, c) = sqrt(-2 ln U(.., 2c)) cos(2 pi U(.., 2c + 1))
"""

from __future__ import annotations

import math

import numpy as np

GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_TWO_53 = 2.0**-53


def splitmix64(x: np.ndarray | np.uint64) -> np.ndarray:
    """SplitMix64's step and finaliser on uint64 values (wrapping arithmetic)."""
    with np.errstate(over="ignore"):
        z = np.asarray(x, dtype=np.uint64) + GOLDEN
        z = (z ^ (z >> _S30)) * _M1
        z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


def stream_key(seed: int, stream: int) -> np.uint64:
    """The key of one stream of a seed (seed and stream: non-negative integers below 2^64)."""
    return np.uint64(splitmix64(np.uint64(seed) ^ splitmix64(np.uint64(stream))))


def normals(seed: int, stream: int, k0: int, n: int, channels: int) -> np.ndarray:
    """Standard normals [n, channels] for samples k0 .. k0 + n - 1 of a stream."""
    key = stream_key(seed, stream)
    k = np.arange(k0, k0 + n, dtype=np.uint64)
    per_sample = splitmix64(key ^ k)[:, None]
    d = np.arange(2 * channels, dtype=np.uint64)[None, :]
    u = splitmix64(per_sample ^ d)
    U = ((u >> _S11).astype(np.float64) + 0.5) * _TWO_53
    # log and cos by libm (math), as the C twin computes them: numpy's own vectorised log and
    # cos may differ from libm's in the last bit
    count = n * channels
    log_u = np.fromiter(map(math.log, U[:, 0::2].ravel().tolist()), float, count)
    cos_v = np.fromiter(map(math.cos, (2.0 * np.pi * U[:, 1::2]).ravel().tolist()), float, count)
    return (np.sqrt(-2.0 * log_u) * cos_v).reshape(n, channels)


class NormalBlocks:
    """The normals of one stream sample by sample, computed a block of samples at a time (the
    noise of sample k is the same whatever the block boundaries)."""

    BLOCK = 1024
    """Samples per block. The block is one numpy array (not Python lists of floats, whose many
    small objects a process freeing and creating sensor instances keeps as fragmented heap)."""

    def __init__(self, seed: int, stream: int, channels: int) -> None:
        self.seed, self.stream, self.channels = seed, stream, channels
        self._k0 = -1
        self._block = np.empty((0, channels))

    def at(self, k: int) -> list[float]:
        """The channels' normals of sample k."""
        i = k - self._k0
        if self._k0 < 0 or not 0 <= i < len(self._block):
            self._k0 = k
            self._block = normals(self.seed, self.stream, k, self.BLOCK, self.channels)
            i = 0
        return self._block[i].tolist()  # type: ignore[no-any-return]


__all__ = ["NormalBlocks", "normals", "splitmix64", "stream_key"]
