"""Compiled silhouette kernels: binarization of uint8 frames, row runs, 8-connected labels,
bounding box, area resampling.

This is the fast implementation of steps 1-4 of :mod:`handsynth.render._preprocess`
(binarize, wrist cut, largest component, crop and resize).  It works on
*runs* (maximal horizontal stretches of foreground pixels in one row): a
720x480 hand mask has about 10^3 runs against 3.5x10^5 pixels, so every
step after the single scan of the image is cheap.

0. A uint8 frame is binarized one row at a time, only inside the kept
   interval of the row, straight into bits (bit ``i`` of a word: pixel
   ``i``); no full-size grey image or mask is made.  Otsu's threshold comes
   from a histogram of every :data:`OTSU_STEP`-th pixel of every
   :data:`OTSU_STEP`-th row (:func:`_frame_threshold`).  The grey level of
   a BGR pixel is computed exactly as OpenCV's ``COLOR_BGR2GRAY`` does, in
   16-bit integer lanes, 32 pixels per SIMD block (:func:`_bgr_t`, emitted
   as LLVM vector IR because numba would widen integer arithmetic to 64
   bits).
1. The scan emits the runs of each row inside that row's kept interval
   ``[lo[y], hi[y])`` (the wrist cut is a half-plane, so what it keeps of a
   row is one interval), finding each change between background and hand
   with a count of trailing zero bits (of the row's bits for a frame, of
   its bytes as 64-bit words for a bool mask).
2. Union-find over runs joins two runs of adjacent rows when their column
   ranges overlap or touch diagonally (8-connectivity).
3. The largest component (pixel count; ties: the one whose first pixel
   comes first in raster order, as OpenCV labels) gives the bounding box;
   a component of fewer pixels than the caller's ``min_area`` gives an
   empty silhouette (too little to be a hand).
4. Area resampling: the box of ``bw x bh`` pixels is scaled by
   ``s = size / max(bw, bh)`` and centred; output cell ``(i, j)`` gets the
   exact area of the component inside it (in cell units).  Each run adds
   one rectangle: partial cells at its ends directly, the full cells
   between them through a per-row difference array.

:func:`handsynth.render._preprocess.crop_resize` states the same
resampling with dense weight matrices; tests compare the two.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from ..errors import InvalidInputError

__all__ = ["MIN_CONTRAST", "OTSU_STEP", "binarize_frame", "silhouette_from_frame", "silhouette_from_mask"]


_ONES = np.uint64(0x0101010101010101)  # eight True bytes
_ALL = np.uint64(0xFFFFFFFFFFFFFFFF)
_U = np.uint64  # array indices of this type compile without negative-index handling


@intrinsic
def _ctz(typingctx, x):
    """Count of trailing zero bits of a nonzero 64-bit integer (one instruction)."""
    if not (isinstance(x, types.Integer) and x.bitwidth == 64):
        return None

    def codegen(context, builder, sig, args):
        fnty = ir.FunctionType(ir.IntType(64), [ir.IntType(64), ir.IntType(1)])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.cttz.i64")
        return builder.call(fn, [args[0], ir.Constant(ir.IntType(1), 1)])

    return types.int64(x), codegen


@njit(cache=True, nogil=True, inline="always")
def _put_run(ry, rx0, rx1, i, y, x0, x1):
    """Store run ``i`` (row `y`, columns ``[x0, x1)``) and return ``i + 1``."""
    ry[_U(i)] = y
    rx0[_U(i)] = x0
    rx1[_U(i)] = x1
    return i + 1


@njit(cache=True, nogil=True)
def _byte_runs(words, wb, x0, x1, y, ry, rx0, rx1, n):
    """Append the runs inside ``[x0, x1)`` of one row of 0/1 bytes, as row `y`.

    The row is ``words[wb:]`` (uint64; pixel ``8k + i`` is byte `i` of word
    ``wb + k``).  Whole words (four at a time) of background outside a run,
    or of foreground inside one, are skipped; inside a word the next change
    is found with :func:`_ctz`.  The run arrays must have room for
    ``(x1 - x0 + 1) // 2`` more runs.  Returns the new run count.
    """
    x0 = max(x0, 0)
    if x0 >= x1:
        return n
    klast = (x1 - 1) >> 3  # the last word; its bytes from x1 on are ignored
    lastmask = _ALL >> _U(64 - 8 * (((x1 - 1) & 7) + 1))
    k = x0 >> 3
    p = x0  # pixels before p are done
    start = 0
    fg = False
    while True:
        if p == (k << 3):  # at a word boundary: skip whole words
            if fg:
                while k + 4 <= klast and (words[_U(wb + k)] & words[_U(wb + k + 1)]
                                          & words[_U(wb + k + 2)]
                                          & words[_U(wb + k + 3)]) == _ONES:
                    k += 4
            else:
                while k + 4 <= klast and (words[_U(wb + k)] | words[_U(wb + k + 1)]
                                          | words[_U(wb + k + 2)]
                                          | words[_U(wb + k + 3)]) == 0:
                    k += 4
            p = k << 3
        w = words[_U(wb + k)]
        if k == klast:
            w &= lastmask
        if fg:
            w ^= _ONES  # nonzero bytes: background
        sh = _U(8 * (p - (k << 3)))
        w = (w >> sh) << sh
        if w == 0:
            k += 1
            if k > klast:
                break
            p = k << 3
            continue
        p = (k << 3) + (_ctz(w) >> 3)
        if fg:
            n = _put_run(ry, rx0, rx1, n, y, start, p)
        else:
            start = p
        fg = not fg
    if fg:
        n = _put_run(ry, rx0, rx1, n, y, start, x1)
    return n


@njit(cache=True, nogil=True)
def _grow(a, n, cap):
    b = np.empty(cap, np.int32)
    b[:n] = a[:n]
    return b


@njit(cache=True, nogil=True)
def _run_buffers(cap):
    """Empty run buffers ``(row, x0, x1)`` for `cap` runs."""
    return np.empty(cap, np.int32), np.empty(cap, np.int32), np.empty(cap, np.int32)


@njit(cache=True, nogil=True)
def _with_room(ry, rx0, rx1, n, room):
    """The run buffers, grown (contents ``[:n]`` kept) when fewer than `room`
    runs fit after run `n`."""
    if n + room <= ry.size:
        return ry, rx0, rx1
    cap = 2 * ry.size + room
    return _grow(ry, n, cap), _grow(rx0, n, cap), _grow(rx1, n, cap)


@njit(cache=True, nogil=True)
def _scan_runs(mask, words, lo, hi):
    """Runs ``(row, x0, x1)`` (x1 exclusive) of a uint8 mask inside ``[lo[y], hi[y])``.

    `words` is the same mask viewed as uint64 (eight pixels per word, shape
    (H, W // 8)) when the width allows it, else shape (H, 0) (each row is
    then copied into a word-aligned buffer).
    """
    h, w = mask.shape
    nw = words.shape[1]
    if nw > 0:
        wflat = words.reshape(words.size)
    else:
        nw = (w + 7) // 8
        wflat = np.zeros(nw, np.uint64)
        row = wflat.view(np.uint8)
    room = (w + 1) // 2  # most runs one row can add
    ry, rx0, rx1 = _run_buffers(4096)
    n = 0
    y = 0
    while y < h:
        ry, rx0, rx1 = _with_room(ry, rx0, rx1, n, room)  # rare; kept out of the row loop
        while y < h and n + room <= ry.size:
            if words.shape[1] > 0:
                n = _byte_runs(wflat, y * nw, lo[y], min(hi[y], w), y, ry, rx0, rx1, n)
            else:
                row[:w] = mask[y]
                n = _byte_runs(wflat, 0, lo[y], min(hi[y], w), y, ry, rx0, rx1, n)
            y += 1
    return ry[:n], rx0[:n], rx1[:n]


@njit(cache=True, nogil=True)
def _find(parent, i):
    root = i
    while parent[root] != root:
        root = parent[root]
    while parent[i] != root:  # path compression
        nxt = parent[i]
        parent[i] = root
        i = nxt
    return root


@njit(cache=True, nogil=True)
def _largest_component(ry, rx0, rx1):
    """Per run, whether it belongs to the largest 8-connected component."""
    n = ry.size
    parent = np.arange(n)
    prev_start = 0  # first run of the previous row
    prev_end = 0  # one past its last run
    i = 0
    while i < n:
        y = ry[i]
        j = i
        while j < n and ry[j] == y:
            j += 1
        if prev_end > prev_start and ry[prev_start] == y - 1:
            k = prev_start
            for r in range(i, j):
                while k < prev_end and rx1[k] < rx0[r]:  # ends left of r, not touching
                    k += 1
                m = k
                while m < prev_end and rx0[m] <= rx1[r]:
                    a = _find(parent, r)
                    b = _find(parent, m)
                    if a != b:  # the smaller index is the root: roots mark first runs
                        if a < b:
                            parent[b] = a
                        else:
                            parent[a] = b
                    m += 1
        prev_start, prev_end = i, j
        i = j
    area = np.zeros(n, np.int64)
    for r in range(n):
        area[_find(parent, r)] += rx1[r] - rx0[r]
    best = -1
    for r in range(n):  # in raster order: ties go to the component seen first
        if parent[r] == r and (best < 0 or area[r] > area[best]):
            best = r
    keep = np.zeros(n, np.bool_)
    for r in range(n):
        keep[r] = parent[r] == best  # parent is fully compressed after the area pass
    return keep


@njit(cache=True, nogil=True)
def _add_span(direct, diff, i, a, b, wgt, size):
    """Add weight `wgt` times the overlap of ``[a, b)`` with each cell of row `i`."""
    if b <= 0.0 or a >= size:
        return
    a = max(a, 0.0)
    b = min(b, float(size))
    ja = int(math.floor(a))
    jb = int(math.floor(b))
    if jb >= size:
        jb = size - 1
    if ja == jb:
        direct[i, ja] += wgt * (b - a)
        return
    direct[i, ja] += wgt * (ja + 1 - a)
    direct[i, jb] += wgt * (b - jb)
    diff[i, ja + 1] += wgt
    diff[i, jb] -= wgt


@njit(cache=True, nogil=True)
def _silhouette(ry, rx0, rx1, size, min_area):
    """Steps 3-4 on the runs: the largest component, cropped and area-resampled; all False
    when that component has fewer than `min_area` pixels."""
    out = np.zeros((size, size), np.bool_)
    if ry.size == 0:
        return out
    keep = _largest_component(ry, rx0, rx1)
    if min_area > 0:
        area = 0
        for r in range(ry.size):
            if keep[r]:
                area += rx1[r] - rx0[r]
        if area < min_area:  # too little to be a hand
            return out
    xmin = 1 << 30
    xmax = -1
    ymin = 1 << 30
    ymax = -1
    for r in range(ry.size):
        if keep[r]:
            xmin = min(xmin, rx0[r])
            xmax = max(xmax, rx1[r])
            ymin = min(ymin, ry[r])
            ymax = max(ymax, ry[r] + 1)
    bw = xmax - xmin
    bh = ymax - ymin
    s = size / max(bw, bh)
    ox = 0.5 * (size - bw * s)
    oy = 0.5 * (size - bh * s)
    direct = np.zeros((size, size))
    diff = np.zeros((size, size + 1))
    for r in range(ry.size):
        if not keep[r]:
            continue
        ya = oy + (ry[r] - ymin) * s
        yb = ya + s
        xa = ox + (rx0[r] - xmin) * s
        xb = ox + (rx1[r] - xmin) * s
        i0 = max(int(math.floor(ya)), 0)
        i1 = min(int(math.ceil(yb)), size)
        for i in range(i0, i1):
            wy = min(yb, i + 1.0) - max(ya, float(i))
            if wy > 0.0:
                _add_span(direct, diff, i, xa, xb, wy, size)
    for i in range(size):
        run = 0.0
        for j in range(size):
            run += diff[i, j]
            out[i, j] = direct[i, j] + run >= 0.5 - 1e-9
    return out


@njit(cache=True, nogil=True)
def _kernel(mask, words, lo, hi, size, min_area):
    ry, rx0, rx1 = _scan_runs(mask, words, lo, hi)
    return _silhouette(ry, rx0, rx1, size, min_area)


# ---------------------------------------------------------------- uint8 frames
#
# Grey level of a BGR pixel (OpenCV's COLOR_BGR2GRAY for uint8: BT.601 weights
# 0.114, 0.587, 0.299 in 15-bit fixed point):
#     grey = (3735 B + 19235 G + 9798 R + 2**14) >> 15.
# Split each weight as 128 a + b (3735 = 128*29 + 23, 19235 = 128*150 + 35,
# 9798 = 128*76 + 70) and let
#     T = (29 B + 150 G + 76 R) + ((23 B + 35 G + 70 R) >> 7)   (<= 65280),
# so that 3735 B + 19235 G + 9798 R = 128 T + r with 0 <= r < 128.  Then
#     grey = (T + 128) >> 8   and   grey > t  <=>  T >= 256 t + 128,
# all of it exact in 16-bit integers (32 pixels in one 512-bit register).

#: Otsu's threshold is taken from the pixels ``(y, x)`` with `y` and `x` both
#: multiples of this step (every 16th pixel).
OTSU_STEP = 4

#: A uint8 frame whose sample (:data:`OTSU_STEP`) spans fewer grey levels than this shows
#: no hand: a flat grey, white (overexposed) or covered view with its compression noise,
#: which Otsu's threshold would split into a random silhouette (values 126 and 128 of a
#: grey MJPG video were read by a learnt estimator as a hand with confidence 0.74-0.79).
#: A hand on the dimmest frames studied spans 35 levels (docs/camera_estimator.md,
#: "Imaging on a dark background").  Frames of only 0 and 1 (masks as uint8) are exempt.
#: A constant compiled into the threshold (assigning it changes nothing).  The rule reads
#: the sample's extremes: a flat view with a dark bar or a bright overlay spans more and
#: is still split by the threshold.
MIN_CONTRAST = 12

_LANES = 32  # pixels per SIMD block
_I8, _I16, _I32 = ir.IntType(8), ir.IntType(16), ir.IntType(32)


def _bgr_t(builder, ptr, step):
    """IR: T (above) of the `_LANES` BGR pixels at ``ptr + 3 * step * i`` (<32 x i16>)."""
    nbytes = 3 * step * (_LANES - 1) + 3
    v = builder.load(builder.bitcast(ptr, ir.PointerType(ir.VectorType(_I8, nbytes))), align=1)
    undef = ir.Constant(v.type, None)
    vt = ir.VectorType(_I16, _LANES)
    chan = [builder.zext(builder.shuffle_vector(
        v, undef, ir.Constant(ir.VectorType(_I32, _LANES),
                              [3 * step * i + c for i in range(_LANES)])), vt)
        for c in range(3)]

    def dot(wts):
        acc = builder.mul(chan[0], ir.Constant(vt, [wts[0]] * _LANES))
        acc = builder.add(acc, builder.mul(chan[1], ir.Constant(vt, [wts[1]] * _LANES)))
        return builder.add(acc, builder.mul(chan[2], ir.Constant(vt, [wts[2]] * _LANES)))

    return builder.add(dot((29, 150, 76)),
                       builder.lshr(dot((23, 35, 70)), ir.Constant(vt, [7] * _LANES)))


def _byte_arrays(*tys):
    return all(isinstance(t, types.Array) and t.ndim == 1 and t.layout == "C"
               and t.dtype == types.uint8 for t in tys)


def _splat16(builder, value):
    vt = ir.VectorType(_I16, _LANES)
    v = builder.insert_element(ir.Constant(vt, None), builder.trunc(value, _I16),
                               ir.Constant(_I32, 0))
    return builder.shuffle_vector(v, ir.Constant(vt, None),
                                  ir.Constant(ir.VectorType(_I32, _LANES), [0] * _LANES))


@intrinsic
def _bgr_flags(typingctx, src, sp, dst, dp, kh):
    """``dst[dp + i] = T(pixel at src[sp + 3 i]) >= kh`` for ``i < 32`` (``0 <= kh < 2**16``).

    The caller guarantees ``src[sp:sp + 96]`` and ``dst[dp:dp + 32]`` are in bounds.
    """
    if not (_byte_arrays(src, dst) and all(isinstance(t, types.Integer) for t in (sp, dp, kh))):
        return None

    def codegen(context, builder, sig, args):
        s = context.make_array(sig.args[0])(context, builder, args[0])
        d = context.make_array(sig.args[2])(context, builder, args[2])
        t = _bgr_t(builder, builder.gep(s.data, [args[1]]), 1)
        flags = builder.zext(builder.icmp_unsigned(">=", t, _splat16(builder, args[4])),
                             ir.VectorType(_I8, _LANES))
        out = builder.bitcast(builder.gep(d.data, [args[3]]),
                              ir.PointerType(ir.VectorType(_I8, _LANES)))
        builder.store(flags, out, align=1)
        return context.get_dummy_value()

    return types.void(src, sp, dst, dp, kh), codegen


@intrinsic
def _bgr_grey_sampled(typingctx, src, sp, dst, dp):
    """``dst[dp + i] = grey(pixel at src[sp + 3 OTSU_STEP i])`` for ``i < 32``.

    The caller guarantees ``src[sp:sp + 3 OTSU_STEP 31 + 3]`` and
    ``dst[dp:dp + 32]`` are in bounds.
    """
    if not (_byte_arrays(src, dst) and all(isinstance(t, types.Integer) for t in (sp, dp))):
        return None

    def codegen(context, builder, sig, args):
        s = context.make_array(sig.args[0])(context, builder, args[0])
        d = context.make_array(sig.args[2])(context, builder, args[2])
        t = _bgr_t(builder, builder.gep(s.data, [args[1]]), OTSU_STEP)
        vt = ir.VectorType(_I16, _LANES)
        grey = builder.lshr(builder.add(t, ir.Constant(vt, [128] * _LANES)),
                            ir.Constant(vt, [8] * _LANES))
        out = builder.bitcast(builder.gep(d.data, [args[3]]),
                              ir.PointerType(ir.VectorType(_I8, _LANES)))
        builder.store(builder.trunc(grey, ir.VectorType(_I8, _LANES)), out, align=1)
        return context.get_dummy_value()

    return types.void(src, sp, dst, dp), codegen


@intrinsic
def _bgr_bits(typingctx, src, sp, kh):
    """Bit `i` (of a uint64 below ``2**32``): ``T(pixel at src[sp + 3 i]) >= kh``, ``i < 32``.

    ``0 <= kh < 2**16``; the caller guarantees ``src[sp:sp + 96]`` is in bounds.
    """
    if not (_byte_arrays(src) and all(isinstance(t, types.Integer) for t in (sp, kh))):
        return None

    def codegen(context, builder, sig, args):
        s = context.make_array(sig.args[0])(context, builder, args[0])
        t = _bgr_t(builder, builder.gep(s.data, [args[1]]), 1)
        bits = builder.bitcast(builder.icmp_unsigned(">=", t, _splat16(builder, args[2])), _I32)
        return builder.zext(bits, ir.IntType(64))

    return types.uint64(src, sp, kh), codegen


@intrinsic
def _grey_bits(typingctx, src, sp, kg):
    """Bit `i` (of a uint64 below ``2**32``): ``src[sp + i] >= kg``, ``i < 32``.

    ``0 <= kg <= 256``; the caller guarantees ``src[sp:sp + 32]`` is in bounds.
    """
    if not (_byte_arrays(src) and all(isinstance(t, types.Integer) for t in (sp, kg))):
        return None

    def codegen(context, builder, sig, args):
        s = context.make_array(sig.args[0])(context, builder, args[0])
        ptr = builder.bitcast(builder.gep(s.data, [args[1]]),
                              ir.PointerType(ir.VectorType(_I8, _LANES)))
        v = builder.zext(builder.load(ptr, align=1), ir.VectorType(_I16, _LANES))
        bits = builder.bitcast(builder.icmp_unsigned(">=", v, _splat16(builder, args[2])), _I32)
        return builder.zext(bits, ir.IntType(64))

    return types.uint64(src, sp, kg), codegen


@njit(cache=True, nogil=True)
def _bgr_t_scalar(src, p):
    b = np.int64(src[_U(p)])
    g = np.int64(src[_U(p + 1)])
    r = np.int64(src[_U(p + 2)])
    return 29 * b + 150 * g + 76 * r + ((23 * b + 35 * g + 70 * r) >> 7)


@njit(cache=True, nogil=True)
def _grey_histogram(src, h, w, nch):
    """Histogram (256 bins) of the grey levels of the :data:`OTSU_STEP` sample.

    `src` is the frame flattened (``nch`` 1: grey, 3: BGR).  Four partial
    histograms break the store-to-load chains of repeated levels.
    """
    hist = np.zeros(4 * 256, np.int64)
    nx = (w + OTSU_STEP - 1) // OTSU_STEP  # samples per row
    buf = np.empty(nx, np.uint8)
    for y in range(0, h, OTSU_STEP):
        base = y * w
        if nch == 3:
            i = 0
            while 3 * OTSU_STEP * (i + _LANES - 1) + 3 <= 3 * w:
                _bgr_grey_sampled(src, 3 * (base + OTSU_STEP * i), buf, i)
                i += _LANES
            for j in range(i, nx):
                buf[j] = (_bgr_t_scalar(src, 3 * (base + OTSU_STEP * j)) + 128) >> 8
            for j in range(nx):
                hist[_U(((j & 3) << 8) | buf[j])] += 1
        else:
            for j in range(nx):
                hist[_U(((j & 3) << 8) | src[_U(base + OTSU_STEP * j)])] += 1
    return hist[:256] + hist[256:512] + hist[512:768] + hist[768:]


@njit(cache=True, nogil=True)
def _otsu(hist):
    """Otsu's threshold of a 256-bin histogram, as OpenCV's ``THRESH_OTSU`` computes it.

    The level `t` maximising the between-class variance of ``{<= t}`` and
    ``{> t}`` (the first such level; 0 when all counts are in one bin), with
    OpenCV's floating-point steps, so that the two agree exactly.
    """
    n = 0
    mu = 0.0
    for i in range(256):
        n += hist[i]
        mu += i * float(hist[i])
    scale = 1.0 / n
    mu *= scale
    eps = 1.1920928955078125e-07  # FLT_EPSILON
    mu1 = 0.0
    q1 = 0.0
    max_sigma = 0.0
    max_val = 0
    for i in range(256):
        p_i = hist[i] * scale
        mu1 *= q1
        q1 += p_i
        q2 = 1.0 - q1
        if min(q1, q2) < eps or max(q1, q2) > 1.0 - eps:
            continue
        mu1 = (mu1 + i * p_i) / q1
        mu2 = (mu - q1 * mu1) / q2
        sigma = q1 * q2 * (mu1 - mu2) * (mu1 - mu2)
        if sigma > max_sigma:
            max_sigma = sigma
            max_val = i
    return max_val


@njit(cache=True, nogil=True)
def _frame_threshold(frame):
    """Otsu's threshold of the sample's histogram; -1 when the samples share one level or,
    above 1, span fewer than :data:`MIN_CONTRAST` levels (no hand)."""
    h, w = frame.shape[0], frame.shape[1]
    src = frame.reshape(frame.size)
    hist = _grey_histogram(src, h, w, frame.size // (h * w))
    lo, hi = -1, -1
    for i in range(256):
        if hist[i] > 0:
            if lo < 0:
                lo = i
            hi = i
    if hi == lo or (hi > 1 and hi - lo < MIN_CONTRAST):
        return -1
    return _otsu(hist)


@njit(cache=True, nogil=True)
def _flag_row(src, nch, base, x0, x1, t, dst, dbase):
    """``dst[dbase + x] = grey(pixel base + x of src) > t`` for x in ``[x0, x1)``, ``t >= -1``."""
    n = x1 - x0
    if nch == 3:
        kh = max(256 * t + 128, 0)  # T >= kh
        p = 3 * (base + x0)
        q = dbase + x0
        i = 0
        while i + _LANES <= n:
            _bgr_flags(src, p + 3 * i, dst, q + i, kh)
            i += _LANES
        if i < n:
            if n >= _LANES:  # one more block, overlapping the last one
                _bgr_flags(src, p + 3 * (n - _LANES), dst, q + n - _LANES, kh)
            else:
                for j in range(i, n):
                    dst[_U(q + j)] = _bgr_t_scalar(src, p + 3 * j) >= kh
    else:
        for i in range(n):
            dst[_U(dbase + x0 + i)] = np.int64(src[_U(base + x0 + i)]) > t


@njit(cache=True, nogil=True)
def _binarize_frame(frame, t):
    h, w = frame.shape[0], frame.shape[1]
    src = frame.reshape(frame.size)
    nch = frame.size // (h * w)
    out = np.empty(h * w, np.uint8)
    for y in range(h):
        _flag_row(src, nch, y * w, 0, w, t, out, y * w)
    return out.reshape((h, w))


@njit(cache=True, nogil=True)
def _bit_row(src, nch, p, n, t, bits):
    """``grey > t`` for the `n` pixels from pixel `p` of flat `src`, as bits.

    Pixel ``p + i`` is bit ``i % 32`` of ``bits[i // 32]`` (uint32); the
    bits after the last pixel, to the end of the next uint64, are 0.
    """
    nfull = n >> 5
    if nch == 3:
        k = max(256 * t + 128, 0)  # grey > t <=> T >= k
        for m in range(nfull):
            bits[_U(m)] = np.uint32(_bgr_bits(src, 3 * (p + 32 * m), k))
    else:
        k = t + 1  # grey >= k
        for m in range(nfull):
            bits[_U(m)] = np.uint32(_grey_bits(src, p + 32 * m, k))
    r = n - (nfull << 5)
    if r > 0:
        if n >= _LANES:  # the block of the last 32 pixels, shifted
            if nch == 3:
                last = _bgr_bits(src, 3 * (p + n - _LANES), k)
            else:
                last = _grey_bits(src, p + n - _LANES, k)
            bits[_U(nfull)] = np.uint32(last >> _U(_LANES - r))
        else:  # a row shorter than a block
            few = 0
            for j in range(n):
                if nch == 3:
                    few |= np.int64(_bgr_t_scalar(src, 3 * (p + j)) >= k) << j
                else:
                    few |= np.int64(np.int64(src[_U(p + j)]) >= k) << j
            bits[_U(0)] = np.uint32(few)
        nfull += 1
    bits[_U(nfull)] = 0
    bits[_U(nfull + 1)] = 0


@njit(cache=True, nogil=True)
def _bit_runs(words, n, x0, y, ry, rx0, rx1, cnt):
    """Append the runs of an `n`-pixel row of bits (uint64 `words`, pixel ``x0 + i``
    is bit ``i % 64`` of ``words[i // 64]``), as row `y`; returns the new count.

    Each change between background and hand is a set bit of ``w ^ (w << 1)``,
    visited with :func:`_ctz`.
    """
    nw = (n + 63) >> 6
    lastmask = _ALL >> _U((nw << 6) - n)
    prev = _U(0)
    start = 0
    fg = False
    for k in range(nw):
        w = words[_U(k)]
        if k == nw - 1:
            w &= lastmask
        tr = w ^ ((w << _U(1)) | prev)
        prev = w >> _U(63)
        while tr != 0:
            p = x0 + (k << 6) + _ctz(tr)
            tr &= tr - _U(1)
            if fg:
                cnt = _put_run(ry, rx0, rx1, cnt, y, start, p)
            else:
                start = p
            fg = not fg
    if fg:
        cnt = _put_run(ry, rx0, rx1, cnt, y, start, x0 + n)
    return cnt


@njit(cache=True, nogil=True)
def _frame_kernel(frame, lo, hi, t, size, min_area):
    """Steps 1-4 of a uint8 frame, one row of bits at a time; ``t == -2``: Otsu's
    threshold of the sample (:func:`_frame_threshold`), else ``grey > t``; all False
    when the largest component has fewer than `min_area` pixels."""
    h, w = frame.shape[0], frame.shape[1]
    if t == -2:
        t = _frame_threshold(frame)
        if t < 0:
            return np.zeros((size, size), np.bool_)
    src = frame.reshape(frame.size)
    nch = frame.size // (h * w)
    nb = (w + 31) // 32 + 3
    bits = np.zeros(nb + (nb & 1), np.uint32)
    words = bits.view(np.uint64)
    room = (w + 1) // 2  # most runs one row can add
    ry, rx0, rx1 = _run_buffers(4096)
    n = 0
    y = 0
    while y < h:
        ry, rx0, rx1 = _with_room(ry, rx0, rx1, n, room)  # rare; kept out of the row loop
        while y < h and n + room <= ry.size:
            x0 = max(lo[y], 0)
            x1 = min(hi[y], w)
            if x0 < x1:
                _bit_row(src, nch, y * w + x0, x1 - x0, t, bits)
                n = _bit_runs(words, x1 - x0, x0, y, ry, rx0, rx1, n)
            y += 1
    return _silhouette(ry[:n], rx0[:n], rx1[:n], size, min_area)


def _threshold(threshold) -> int:
    """A fixed threshold as the level `t` of ``grey > t``, clipped to [-1, 255].

    Raises
    ------
    InvalidInputError
        `threshold` is not a finite real number (a bool, a string, NaN or
        inf), naming it and the value received.
    """
    if isinstance(threshold, bool) or not isinstance(threshold, (int, float, np.integer,
                                                                 np.floating)) \
            or not math.isfinite(threshold):
        raise InvalidInputError(
            f"threshold must be a finite number (a grey level, 0-255), got {threshold!r}")
    return min(max(int(threshold), -1), 255)


def binarize_frame(frame: np.ndarray, *, threshold: int | None = None) -> np.ndarray:
    """``grey > t`` for every pixel of a uint8 frame: `t` is `threshold`, or
    Otsu's threshold of its :data:`OTSU_STEP` sample (all False when that is -1).

    Returns
    -------
    ndarray, shape (H, W), bool
    """
    frame = np.ascontiguousarray(frame)
    t = int(_frame_threshold(frame)) if threshold is None else _threshold(threshold)
    if threshold is None and t < 0:
        return np.zeros(frame.shape[:2], dtype=bool)
    return _binarize_frame(frame, t).view(np.bool_)


def silhouette_from_frame(frame: np.ndarray, lo: np.ndarray, hi: np.ndarray, size: int, *,
                          threshold: int | None = None, min_area: int = 0) -> np.ndarray:
    """:func:`silhouette_from_mask` of ``binarize_frame(frame, threshold=threshold)``,
    without making the mask.

    Parameters
    ----------
    frame : ndarray, shape (H, W) or (H, W, 3), uint8
    lo, hi : ndarray, shape (H,), int32
    size : int
    threshold : int, keyword-only, optional
    min_area : int, keyword-only
        As for :func:`silhouette_from_mask`.

    Returns
    -------
    ndarray, shape (size, size), bool
    """
    t = -2 if threshold is None else _threshold(threshold)
    return _frame_kernel(np.ascontiguousarray(frame), lo, hi, t, int(size), int(min_area))


def silhouette_from_mask(mask: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                         size: int, *, min_area: int = 0) -> np.ndarray:
    """The ``size x size`` silhouette of a bool mask (steps 2-4 of the preprocessing).

    Parameters
    ----------
    mask : ndarray, shape (H, W), bool
    lo, hi : ndarray, shape (H,), int32
        Kept columns of each row, ``[lo[y], hi[y])`` (the wrist cut).
    size : int
    min_area : int, keyword-only
        Fewest pixels of the kept (largest) component: a smaller one gives an
        all-False silhouette (no hand).  The component's pixel count comes
        from the same pass over the runs, at no extra cost.

    Returns
    -------
    ndarray, shape (size, size), bool
    """
    m = np.ascontiguousarray(mask).view(np.uint8)
    if m.shape[1] % 8 == 0:
        words = m.view(np.uint64)
    else:
        words = np.empty((m.shape[0], 0), np.uint64)
    return _kernel(m, words, lo, hi, int(size), int(min_area))
