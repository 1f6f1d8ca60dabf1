#!/usr/bin/env python3
"""How much a pixel's sample positions can do at an edge: the error of N samples estimating the
covered fraction of a pixel (the unit square) cut by a straight edge of uniform direction through
a uniform point of the pixel, for several ways of placing the samples, as RMSE relative to the
jittered grid (the independent sampler's pixel positions, camera/pixel_sampler.hpp). Each point
set is randomised so that every sample is uniform over the pixel (the estimate is unbiased).

Issue 32 asks the sobol sampler for 0.7 of the independent sampler's error; at 16 and 64 samples
most of the error left on hw3 metal_plates_area and glossy_area_small lies on edges
(bench/RESULTS.md, "The samplers"). No dependency beyond Python 3.

    python3 bench/edge_sampling.py [TRIALS] [SEED]
"""
import math
import random
import sys


def covered(nx, ny, c):
    """Area of {(x, y) in [0, 1]^2 : nx x + ny y > c} (the square clipped by a half-plane)."""
    square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    kept = []
    for i in range(4):
        p, q = square[i], square[(i + 1) % 4]
        fp, fq = nx * p[0] + ny * p[1] - c, nx * q[0] + ny * q[1] - c
        if fp > 0:
            kept.append(p)
        if (fp > 0) != (fq > 0):
            t = fp / (fp - fq)
            kept.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    area = 0.0
    for i in range(len(kept)):
        (x0, y0), (x1, y1) = kept[i], kept[(i + 1) % len(kept)]
        area += x0 * y1 - x1 * y0
    return abs(area) / 2


def jittered(n, rng):
    side = math.isqrt(n)
    return [((i % side + rng.random()) / side, (i // side + rng.random()) / side) for i in range(n)]


BITS = 24


def sobol_2d(n):
    """The first n points of Sobol' dimensions 0 (van der Corput) and 1, as BITS-bit integers."""
    directions = [1 << (BITS - 1)]
    for _ in range(1, BITS):
        directions.append(directions[-1] ^ (directions[-1] >> 1))
    points = []
    for i in range(n):
        x = y = 0
        for k in range(BITS):
            if (i >> k) & 1:
                x ^= 1 << (BITS - 1 - k)
                y ^= directions[k]
        points.append((x, y))
    return points


def owen(values, rng):
    """Nested uniform scrambling (Owen 1995): each digit flipped by a coin of its prefix's node."""
    flips = {}
    scrambled = []
    for v in values:
        r = 0
        for k in range(BITS):
            node = (k, v >> (BITS - k))
            if node not in flips:
                flips[node] = rng.getrandbits(1)
            r |= (((v >> (BITS - 1 - k)) & 1) ^ flips[node]) << (BITS - 1 - k)
        scrambled.append(r)
    return scrambled


SOBOL = {}


def owen_sobol(n, rng):
    if n not in SOBOL:
        SOBOL[n] = sobol_2d(n)
    xs = owen([p[0] for p in SOBOL[n]], rng)
    ys = owen([p[1] for p in SOBOL[n]], rng)
    scale = 1.0 / (1 << BITS)
    return [((x + rng.random()) * scale, (y + rng.random()) * scale) for x, y in zip(xs, ys)]


def lattice(generator):
    """A rank-1 lattice (i / n, i g / n), shifted at random on the torus and turned by one of the
    square's eight symmetries."""
    def lattice_points(n, rng):
        sx, sy = rng.random(), rng.random()
        points = [((i / n + sx) % 1.0, ((i * generator % n) / n + sy) % 1.0) for i in range(n)]
        symmetry = rng.randrange(8)
        if symmetry & 1:
            points = [(y, x) for x, y in points]
        if symmetry & 2:
            points = [(1 - x, y) for x, y in points]
        if symmetry & 4:
            points = [(x, 1 - y) for x, y in points]
        return points
    return lattice_points


def mean_squared_error(place, n, trials, rng):
    """The mean squared error over `trials` edges; exits if the errors' mean is not within five
    standard errors of zero (a point set whose randomisation is biased, or a wrong area)."""
    total = squares = 0.0
    for _ in range(trials):
        points = place(n, rng)
        angle = rng.random() * 2 * math.pi
        nx, ny = math.cos(angle), math.sin(angle)
        c = nx * rng.random() + ny * rng.random()
        estimate = sum(1 for x, y in points if nx * x + ny * y > c) / n
        error = estimate - covered(nx, ny, c)
        total += error
        squares += error * error
    mean, mse = total / trials, squares / trials
    if abs(mean) > 5 * math.sqrt(max(mse - mean * mean, 0.0) / trials):
        sys.exit(f'edge_sampling: {place.__name__} at N={n}: mean error {mean:.5f}, not an unbiased estimate')
    return mse


def main():
    trials = int(sys.argv[1]) if len(sys.argv) > 1 else 20000
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 1
    layouts = {16: [5, 7, 3], 64: [19, 27, 29, 11]}
    print(f'{trials} edges a row, seed {seed}; RMSE over the jittered grid\'s (its own RMSE in brackets)')
    for n, generators in layouts.items():
        rng = random.Random(seed)
        base = mean_squared_error(jittered, n, trials, rng)
        print(f'N={n:3d} jittered grid           1.000 ({math.sqrt(base):.4f})')
        rows = [('Owen-scrambled Sobol\'', owen_sobol)] + [(f'lattice g={g}', lattice(g)) for g in generators]
        for name, place in rows:
            mse = mean_squared_error(place, n, trials, rng)
            print(f'N={n:3d} {name:24s} {math.sqrt(mse / base):.3f} ({math.sqrt(mse):.4f})', flush=True)


if __name__ == '__main__':
    main()
