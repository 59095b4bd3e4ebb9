//! Conversions between the row-major [`SampleMatrix`] of the trait crate and
//! faer's column-major [`Mat`], plus the few element-wise helpers the kernel
//! code needs and the per-thread recycling of large buffers ([`zeros`],
//! [`recycle`]). Conversions happen at the crate boundary only (STYLE.md).

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef};
use gpodo_traits::SampleMatrix;

mod symmetric;
pub use symmetric::{
    copy_lower_triangle, lower_hadamard_in_place, symmetric_times, symmetrize_from_lower,
};

/// Copies a row-major sample matrix into a faer matrix.
pub fn to_faer(m: &SampleMatrix) -> Mat<f64> {
    Mat::from_fn(m.nrows(), m.ncols(), |i, j| m.get(i, j))
}

/// Copies a faer matrix into a row-major sample matrix.
pub fn from_faer(m: MatRef<'_, f64>) -> SampleMatrix {
    let (n, d) = (m.nrows(), m.ncols());
    let mut data = Vec::with_capacity(n * d);
    for i in 0..n {
        for j in 0..d {
            data.push(m[(i, j)]);
        }
    }
    // Shapes agree by construction.
    SampleMatrix::from_row_major(n, d, data).unwrap_or_else(|_| SampleMatrix::zeros(n, d))
}

/// Matrices smaller than this many entries (512 KiB) are left to the
/// allocator: only the large `n × n` buffers of an evaluation are recycled.
const RECYCLE_MIN_ENTRIES: usize = 1 << 16;
/// The most a thread keeps in spare buffers (bytes). The pool never holds
/// more than the buffers one evaluation had alive at once (each is taken
/// again by the next evaluation), so the cap only has to clear that: at
/// n = 4000 one buffer is 128 MB, and a cap of 256 MiB kept two of them,
/// sending the rest back to the system to be faulted in again (9 % of a
/// fit's CPU time in the kernel). 1 GiB keeps them all; the peak resident
/// memory is unchanged (520 MB for an evaluation loop at n = 4000).
const SPARE_BYTES_PER_THREAD: usize = 1 << 30;

std::thread_local! {
    /// Large matrices handed back by [`recycle`], for [`zeros`] to reuse.
    static SPARE: std::cell::RefCell<Vec<Mat<f64>>> = const { std::cell::RefCell::new(Vec::new()) };
    /// This thread's cap on its spare buffers (bytes).
    static SPARE_LIMIT: std::cell::Cell<usize> = const { std::cell::Cell::new(SPARE_BYTES_PER_THREAD) };
}

/// Raises this thread's cap on spare buffers to at least `bytes` until it
/// is dropped. A fit whose evaluations each need `n × n` buffers larger
/// than the default cap (the iterative exact GP at n = 20 000: three of
/// 3.2 GB) holds them from one evaluation to the next, rather than
/// returning them to the system to be faulted in and zeroed again (a third
/// of its time); its peak memory is the same.
#[derive(Debug)]
pub struct SpareLimit {
    previous: usize,
}

impl SpareLimit {
    /// The cap raised to at least `bytes`.
    pub fn at_least(bytes: usize) -> Self {
        let previous = SPARE_LIMIT.with(|l| l.replace(l.get().max(bytes)));
        Self { previous }
    }
}

impl Drop for SpareLimit {
    fn drop(&mut self) {
        SPARE_LIMIT.with(|l| l.set(self.previous));
    }
}

/// An `nrows × ncols` matrix of zeros, reusing a buffer of that shape that
/// this thread handed to [`recycle`] when there is one.
///
/// An exact-GP evaluation allocates and frees several `n × n` matrices;
/// fresh allocations that large come from the system as untouched pages, so
/// every evaluation paid the kernel for page faults and zeroing again (about
/// 15 % of `paper.yaml`'s fits on two cores). Reusing the buffers removes
/// that; the values are the same, since the buffer is zeroed.
pub fn zeros(nrows: usize, ncols: usize) -> Mat<f64> {
    match take_spare(nrows, ncols) {
        Some(mut m) => {
            m.fill(0.0);
            m
        }
        None => Mat::zeros(nrows, ncols),
    }
}

/// A spare buffer of this shape that this thread handed to [`recycle`],
/// if there is one (large shapes only).
fn take_spare(nrows: usize, ncols: usize) -> Option<Mat<f64>> {
    if nrows * ncols < RECYCLE_MIN_ENTRIES {
        return None;
    }
    SPARE.with(|spare| {
        let mut spare = spare.borrow_mut();
        let at = spare
            .iter()
            .position(|m| m.nrows() == nrows && m.ncols() == ncols)?;
        Some(spare.swap_remove(at))
    })
}

/// An `nrows × ncols` matrix for a caller that overwrites every entry
/// before reading any: a recycled buffer of that shape keeps whatever it
/// held (no zeroing pass over `n²` entries), a fresh one is zeros.
pub fn scratch(nrows: usize, ncols: usize) -> Mat<f64> {
    take_spare(nrows, ncols).unwrap_or_else(|| Mat::zeros(nrows, ncols))
}

/// Hands a matrix no longer needed back to this thread's spare buffers
/// (large ones only, at most 1 GiB per thread unless a [`SpareLimit`]
/// raises it, the oldest dropped first).
pub fn recycle(m: Mat<f64>) {
    let entries = m.nrows() * m.ncols();
    let limit = SPARE_LIMIT.with(std::cell::Cell::get);
    if entries < RECYCLE_MIN_ENTRIES || entries * 8 > limit {
        return;
    }
    SPARE.with(|spare| {
        let mut spare = spare.borrow_mut();
        spare.push(m);
        let bytes = |v: &Vec<Mat<f64>>| v.iter().map(|m| m.nrows() * m.ncols() * 8).sum::<usize>();
        while bytes(&spare) > limit {
            spare.remove(0);
        }
    });
}

/// Frees this thread's spare buffers (after a fit, say).
pub fn release_spare() {
    SPARE.with(|spare| spare.borrow_mut().clear());
}

/// `Σ_ij a_ij b_ij`.
pub fn frobenius_dot(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    debug_assert_eq!((a.nrows(), a.ncols()), (b.nrows(), b.ncols()));
    let mut total = 0.0;
    for j in 0..a.ncols() {
        let (ca, cb) = (column(a, j), column(b, j));
        total += ca.iter().zip(cb.iter()).map(|(x, y)| x * y).sum::<f64>();
    }
    total
}

/// `a ∘ b` (element-wise product).
pub fn hadamard(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    debug_assert_eq!((a.nrows(), a.ncols()), (b.nrows(), b.ncols()));
    let mut out = scratch(a.nrows(), a.ncols());
    for j in 0..a.ncols() {
        let (ca, cb) = (column(a, j), column(b, j));
        for ((o, x), y) in column_mut(&mut out, j)
            .iter_mut()
            .zip(ca.iter())
            .zip(cb.iter())
        {
            *o = x * y;
        }
    }
    out
}

/// The trace of a square matrix.
pub fn trace(a: MatRef<'_, f64>) -> f64 {
    (0..a.nrows().min(a.ncols())).map(|i| a[(i, i)]).sum()
}

/// Column `j` of a column-major matrix as a slice.
///
/// Every matrix in this crate is allocated by faer with unit row stride, so
/// the slice always exists; the fallback copies for foreign views.
pub fn column(a: MatRef<'_, f64>, j: usize) -> std::borrow::Cow<'_, [f64]> {
    match a.col(j).try_as_col_major() {
        Some(c) => std::borrow::Cow::Borrowed(c.as_slice()),
        None => std::borrow::Cow::Owned(a.col(j).iter().copied().collect()),
    }
}

/// Column `j` of an owned matrix as a mutable slice.
pub fn column_mut(a: &mut Mat<f64>, j: usize) -> &mut [f64] {
    a.col_as_slice_mut(j)
}

/// The parallelism used by the dense kernels: faer's global setting, so a
/// sweep that already runs regressors on every core can set it to
/// `Par::Seq` once (`faer::set_global_parallelism`).
pub fn par() -> faer::Par {
    faer::get_global_parallelism()
}

/// Multiply-adds below which [`gemm`] runs sequentially: handing work to
/// Rayon's pool and waiting for it costs microseconds, tens of them when
/// the caller is not one of the pool's threads (a ROS node's callback, a
/// Python call) or the pool's threads are asleep, more than such a product
/// takes on one core. A one-row prediction with 100 inducing points is far
/// below it, and below [`SEQUENTIAL_ENTRIES`].
const SEQUENTIAL_WORK: usize = 1 << 18;

/// Entries below which [`for_column_blocks`] runs sequentially (each entry
/// costs a kernel profile, an `exp` or so: about 10 ns).
const SEQUENTIAL_ENTRIES: usize = 1 << 12;

/// Columns per block of [`for_column_blocks`].
const COLUMN_BLOCK: usize = 64;

/// Runs `f(j0, columns, per_column)` over blocks of up to 64 columns of
/// `out` (`columns` holds columns `j0..j0 + columns.len()` as mutable
/// slices, `per_column` the matching entries of `per_column_out`), in
/// parallel when faer's global parallelism is Rayon. Each block is written
/// by exactly one call and any reduction over `per_column_out` is left to
/// the caller, in column order, so the result is bit-identical whatever
/// the thread count.
pub fn for_column_blocks<T: Send>(
    out: &mut Mat<f64>,
    per_column_out: &mut [T],
    f: impl Fn(usize, &mut [&mut [f64]], &mut [T]) + Sync,
) {
    debug_assert_eq!(per_column_out.len(), out.ncols());
    let run = |b: usize, block: MatMut<'_, f64>, per_column: &mut [T]| {
        // Owned faer matrices are column-major with unit row stride, so
        // every column of a view of one is a slice.
        let mut columns: Vec<&mut [f64]> = block
            .col_iter_mut()
            .filter_map(|c| c.try_as_col_major_mut().map(|c| c.as_slice_mut()))
            .collect();
        debug_assert_eq!(columns.len(), per_column.len());
        f(b * COLUMN_BLOCK, &mut columns, per_column);
    };
    let parallelism = if out.nrows() * out.ncols() < SEQUENTIAL_ENTRIES {
        faer::Par::Seq
    } else {
        par()
    };
    match parallelism {
        faer::Par::Seq => {
            let n = out.ncols();
            for (b, j0) in (0..n).step_by(COLUMN_BLOCK).enumerate() {
                let j1 = (j0 + COLUMN_BLOCK).min(n);
                run(
                    b,
                    out.as_mut().subcols_mut(j0, j1 - j0),
                    &mut per_column_out[j0..j1],
                );
            }
        }
        faer::Par::Rayon(_) => {
            use rayon::prelude::*;
            out.par_col_chunks_mut(COLUMN_BLOCK)
                .zip(per_column_out.par_chunks_mut(COLUMN_BLOCK))
                .enumerate()
                .for_each(|(b, (block, per_column))| run(b, block, per_column));
        }
    }
}

/// `dst = alpha·a·b` (or `dst += …` with [`Accum::Add`]) with faer's GEMM,
/// run sequentially when the product is small (under 2¹⁸ multiply-adds) or
/// the inner dimension dwarfs the output (e.g. `K_uf K_fu`, `m × n` by
/// `n × m` with `n ≫ m`): faer's parallel GEMM splits the output only, and
/// on such shapes it is far slower than its sequential kernel
/// (`bench/README.md`, "Sparse GP").
pub fn gemm(
    dst: MatMut<'_, f64>,
    accum: Accum,
    a: MatRef<'_, f64>,
    b: MatRef<'_, f64>,
    alpha: f64,
) {
    let inner = a.ncols();
    let work = dst.nrows() * dst.ncols() * inner;
    let parallelism = if work < SEQUENTIAL_WORK || inner > 4 * dst.nrows().max(dst.ncols()) {
        faer::Par::Seq
    } else {
        par()
    };
    matmul(dst, accum, a, b, alpha, parallelism);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spare_shapes() -> Vec<(usize, usize)> {
        SPARE.with(|s| s.borrow().iter().map(|m| (m.nrows(), m.ncols())).collect())
    }

    #[test]
    fn recycled_buffers_come_back_zeroed_and_only_when_large() {
        release_spare();
        let n = 300; // 90 000 entries: recycled
        let mut a = zeros(n, n);
        a.fill(7.0);
        let at = a.as_ptr();
        recycle(a);
        assert_eq!(spare_shapes(), vec![(n, n)]);
        // Another shape is not served from it.
        let b = zeros(n, n + 1);
        assert_eq!(spare_shapes(), vec![(n, n)]);
        let again = zeros(n, n);
        assert_eq!(again.as_ptr(), at, "the buffer is reused");
        assert!(again.norm_max() == 0.0, "and zeroed");
        assert!(spare_shapes().is_empty());
        // Small matrices are left to the allocator.
        recycle(Mat::zeros(10, 10));
        assert!(spare_shapes().is_empty());
        drop(b);
    }

    #[test]
    fn scratch_reuses_a_buffer_without_zeroing_it() {
        release_spare();
        let n = 300;
        // Fresh: zeros.
        let mut a = scratch(n, n);
        assert!(a.norm_max() == 0.0);
        a.fill(3.0);
        let at = a.as_ptr();
        recycle(a);
        let again = scratch(n, n);
        assert_eq!(again.as_ptr(), at, "the buffer is reused");
        assert_eq!(again[(n - 1, n - 1)], 3.0, "as it was left");
        assert!(spare_shapes().is_empty());
    }

    #[test]
    fn spare_buffers_stay_within_the_byte_cap() {
        release_spare();
        // 64 MiB each (zeroed by the system, never touched): the cap keeps
        // the newest sixteen.
        let n = 2896;
        for _ in 0..20 {
            recycle(Mat::zeros(n, n));
        }
        let kept = spare_shapes().len();
        assert!(kept * n * n * 8 <= SPARE_BYTES_PER_THREAD, "{kept} kept");
        assert_eq!(kept, SPARE_BYTES_PER_THREAD / (n * n * 8));
        release_spare();
        assert!(spare_shapes().is_empty());
    }
}
