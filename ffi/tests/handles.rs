//! The C ABI's own behaviour seen from Rust: kernels' claims passed on through a
//! handle, the exact solutions' errors and the last-error message.

mod kernels {
    use coagula::*;
    use coagula_core::kernel::{Coagulation, CoagulationKernel};
    use std::ffi::c_void;

    extern "C" fn one(_x: f64, _y: f64, _ud: *mut c_void) -> f64 {
        1.0
    }

    /// A built-in kernel's monotone factors reach the engine through the C handle (its
    /// buckets bounded from their ends); a C callback's never claim it.
    #[test]
    fn monotone_factors_pass_on_for_built_in_kernels_only() {
        assert!(Kernel::Builtin(Coagulation::free_molecular()).monotone_factors());
        let user = coag_user_kernel {
            rate: Some(one),
            majorant: None,
            rank: 0,
            factors: None,
            low_rank_exact: 0,
            sup: None,
            user_data: core::ptr::null_mut(),
        };
        assert!(!Kernel::User(user, Default::default()).monotone_factors());
    }
}

mod exact {
    use coagula::*;
    use std::ffi::c_char;

    #[test]
    fn errors_and_messages() {
        let mut out = -1.0;
        assert_eq!(
            unsafe { coag_exact_moment(COAG_EXACT_CONSTANT, 2, 3.0, &mut out) },
            COAG_OK
        );
        assert_eq!(out, 4.0);
        // the documented scaling: K = b from monomers of concentration c0 is
        // c0 M_m(b c0 t); M0 = c0 / (1 + b c0 t / 2)
        let (b, c0, t) = (3.0, 0.5, 0.7);
        unsafe { coag_exact_moment(COAG_EXACT_CONSTANT, 0, b * c0 * t, &mut out) };
        assert!((c0 * out - c0 / (1.0 + b * c0 * t / 2.0)).abs() < 1e-15);
        for m in [4, 7] {
            assert_eq!(
                unsafe { coag_exact_moment(COAG_EXACT_CONSTANT, m, 1.0, &mut out) },
                COAG_UNSUPPORTED
            );
        }
        assert_eq!(
            unsafe { coag_exact_density(COAG_EXACT_COAG_FRAG, 1, 1.0, &mut out) },
            COAG_UNSUPPORTED
        );
        out = 4.0;
        assert_eq!(
            unsafe { coag_exact_moment(COAG_EXACT_CONSTANT, 2, -3.0, &mut out) },
            COAG_INVALID_ARGUMENT
        );
        assert_eq!(out, 4.0, "outputs untouched on error");
        let mut buf = [0 as c_char; 8];
        let mut len = 0usize;
        assert_eq!(
            unsafe { coag_last_error_message(buf.as_mut_ptr(), buf.len(), &mut len) },
            COAG_BUFFER_TOO_SMALL
        );
        assert!(len > 8);
        let mut big = vec![0 as c_char; len + 1];
        assert_eq!(
            unsafe { coag_last_error_message(big.as_mut_ptr(), big.len(), std::ptr::null_mut()) },
            COAG_OK
        );
        let msg = unsafe { std::ffi::CStr::from_ptr(big.as_ptr()) }
            .to_str()
            .unwrap();
        assert!(msg.contains("t = -3"), "{msg}");
        assert_eq!(
            unsafe { coag_exact_moment(99, 2, 1.0, &mut out) },
            COAG_INVALID_ARGUMENT
        );
        assert_eq!(
            unsafe { coag_exact_moment(0, 2, 1.0, std::ptr::null_mut()) },
            COAG_NULL_PARAMETER
        );
        let v = unsafe { std::ffi::CStr::from_ptr(coag_version()) };
        assert_eq!(v.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
    }
}
