//! The three LAPACK routines of the comparison, declared by hand and wrapped in safe functions
//! for the one size the bench needs (`N × N`, column-major, leading dimension `N`).
//!
//! The library is Debian's reference LAPACK (`liblapack-dev`, installed by `tests/run-all.sh`):
//! LP64 (32-bit `INTEGER`), built with gfortran, so every `CHARACTER` argument is followed by a
//! hidden length (`size_t`) at the end of the argument list. The `#[link]` attribute below is
//! on this module's `extern` block only, so `-llapack` is passed to this bench's binary and to no
//! other target of the package.

// Calling Fortran through raw pointers cannot be checked by the compiler: this module and the
// two libc calls of `sys` in main.rs are the bench's only unsafe code (the crate root denies
// `unsafe_code`), each call documented below.
#![allow(unsafe_code)]

use std::os::raw::{c_char, c_int};

use nalgebra::SMatrix;
use planner_core::window::N;

/// `N` as a LAPACK `INTEGER`.
const NI: c_int = N as c_int;

#[link(name = "lapack")]
extern "C" {
    fn dgetrf_(
        m: *const c_int,
        n: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        ipiv: *mut c_int,
        info: *mut c_int,
    );
    fn dgetrs_(
        trans: *const c_char,
        n: *const c_int,
        nrhs: *const c_int,
        a: *const f64,
        lda: *const c_int,
        ipiv: *const c_int,
        b: *mut f64,
        ldb: *const c_int,
        info: *mut c_int,
        trans_len: usize,
    );
    fn dgesvx_(
        fact: *const c_char,
        trans: *const c_char,
        n: *const c_int,
        nrhs: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        af: *mut f64,
        ldaf: *const c_int,
        ipiv: *mut c_int,
        equed: *mut c_char,
        r: *mut f64,
        c: *mut f64,
        b: *mut f64,
        ldb: *const c_int,
        x: *mut f64,
        ldx: *const c_int,
        rcond: *mut f64,
        ferr: *mut f64,
        berr: *mut f64,
        work: *mut f64,
        iwork: *mut c_int,
        info: *mut c_int,
        fact_len: usize,
        trans_len: usize,
        equed_len: usize,
    );
}

/// Row interchanges of an LU factorisation, as `dgetrf` writes them (1-based).
pub type Pivots = [c_int; N];

/// LU factorisation with partial pivoting in place (`dgetrf`); `Err(info)` if LAPACK reports
/// an illegal argument (`info < 0`) or an exactly zero pivot (`info > 0`).
pub fn dgetrf(a: &mut SMatrix<f64, N, N>, ipiv: &mut Pivots) -> Result<(), i32> {
    let mut info: c_int = 0;
    // SAFETY: `a` is N×N contiguous column-major storage (nalgebra's layout) with leading
    // dimension N, `ipiv` holds N integers, `info` one; dgetrf touches nothing else and keeps
    // no pointer after it returns.
    unsafe {
        dgetrf_(&NI, &NI, a.as_mut_ptr(), &NI, ipiv.as_mut_ptr(), &mut info);
    }
    if info == 0 {
        Ok(())
    } else {
        Err(info)
    }
}

/// Solves `A X = B` for the `K` columns of `b` in place with the factorisation from
/// [`dgetrf`] (`dgetrs`, `TRANS = 'N'`).
pub fn dgetrs<const K: usize>(
    lu: &SMatrix<f64, N, N>,
    ipiv: &Pivots,
    b: &mut [[f64; N]; K],
) -> Result<(), i32> {
    let nrhs = K as c_int;
    let mut info: c_int = 0;
    // SAFETY: `lu` is N×N column-major with leading dimension N (read only), `ipiv` N integers
    // (read only), `b` K contiguous columns of N doubles ([[f64; N]; K] has no padding), so the
    // leading dimension of B is N; TRANS points to one byte and its hidden length is 1.
    unsafe {
        dgetrs_(
            b"N".as_ptr().cast(),
            &NI,
            &nrhs,
            lu.as_ptr(),
            &NI,
            ipiv.as_ptr(),
            b.as_mut_ptr().cast(),
            &NI,
            &mut info,
            1,
        );
    }
    if info == 0 {
        Ok(())
    } else {
        Err(info)
    }
}

/// The workspace of [`Gesvx::solve`]: everything `dgesvx` needs besides the matrices, kept
/// between calls so that the timed loop allocates nothing.
#[derive(Clone, Debug)]
pub struct Gesvx {
    r: [f64; N],
    c: [f64; N],
    work: [f64; 4 * N],
    iwork: [c_int; N],
    ferr: [f64; 1],
    berr: [f64; 1],
}

impl Default for Gesvx {
    fn default() -> Self {
        Self {
            r: [0.0; N],
            c: [0.0; N],
            work: [0.0; 4 * N],
            iwork: [0; N],
            ferr: [0.0],
            berr: [0.0],
        }
    }
}

impl Gesvx {
    /// One right-hand side through the expert driver with a given factorisation (`dgesvx`,
    /// `FACT = 'F'`, `TRANS = 'N'`, `EQUED = 'N'`): a solve, iterative refinement against `a`
    /// (one residual in extra work per step), a condition estimate and error bounds. Writes
    /// the solution into `x` and returns the reciprocal condition number; `Err(info)` for an
    /// illegal argument or a singular `U` (`info = N + 1`, `RCOND` below machine precision,
    /// still has a solution and is returned as `Ok`).
    pub fn solve(
        &mut self,
        a: &mut SMatrix<f64, N, N>,
        af: &mut SMatrix<f64, N, N>,
        ipiv: &mut Pivots,
        b: &mut [f64; N],
        x: &mut [f64; N],
    ) -> Result<f64, i32> {
        let one: c_int = 1;
        let mut equed: c_char = b'N' as c_char;
        let mut rcond = 0.0;
        let mut info: c_int = 0;
        // SAFETY: `a` and `af` are N×N column-major with leading dimension N, `ipiv` N
        // integers, `b` and `x` N doubles (one column each, leading dimension N), `r` and `c` N
        // doubles, `work` 4N, `iwork` N integers, `ferr` and `berr` one double each (NRHS = 1):
        // the sizes dgesvx documents. With FACT = 'F' and EQUED = 'N' it reads `a`, `af`,
        // `ipiv` and `b` and writes only `x`, `rcond`, `ferr`, `berr`, `work`, `iwork` and
        // `info`. The three CHARACTER arguments point to one byte each, hidden lengths 1.
        unsafe {
            dgesvx_(
                b"F".as_ptr().cast(),
                b"N".as_ptr().cast(),
                &NI,
                &one,
                a.as_mut_ptr(),
                &NI,
                af.as_mut_ptr(),
                &NI,
                ipiv.as_mut_ptr(),
                &mut equed,
                self.r.as_mut_ptr(),
                self.c.as_mut_ptr(),
                b.as_mut_ptr(),
                &NI,
                x.as_mut_ptr(),
                &NI,
                &mut rcond,
                self.ferr.as_mut_ptr(),
                self.berr.as_mut_ptr(),
                self.work.as_mut_ptr(),
                self.iwork.as_mut_ptr(),
                &mut info,
                1,
                1,
                1,
            );
        }
        if info == 0 || info == NI + 1 {
            Ok(rcond)
        } else {
            Err(info)
        }
    }
}
