! coagula_types.f90 — the constants, bind(c) derived types and callback interfaces of
! include/coagula.h, for the Fortran module coagula (include/coagula.f90), which uses
! and re-exports them: compile this file first. See coagula.f90 for the conventions.
module coagula_types
  use, intrinsic :: iso_c_binding
  implicit none

  ! statuses
  integer(c_int32_t), parameter :: COAG_OK = 0, COAG_NULL_PARAMETER = 1, COAG_INVALID_ARGUMENT = 2, &
       COAG_BUFFER_TOO_SMALL = 3, COAG_CAPACITY = 4, COAG_INVALID_RATE = 5, COAG_UNSUPPORTED = 6, &
       COAG_TIME_BACKWARDS = 7, COAG_BAD_CHECKPOINT = 8, COAG_PANIC = 9, COAG_INTERRUPTED = 10, &
       COAG_RNG_FAILURE = 11, COAG_REENTRANT = 12
  ! exact solutions (coag_exact_*)
  integer(c_int32_t), parameter :: COAG_EXACT_CONSTANT = 0, COAG_EXACT_ADDITIVE = 1, &
       COAG_EXACT_MULTIPLICATIVE = 2, COAG_EXACT_MARCUS_LUSHNIKOV = 3, COAG_EXACT_COAG_FRAG = 4
  ! a source's sizes (coag_sim_set_source)
  integer(c_int32_t), parameter :: COAG_SOURCE_MONODISPERSE = 0, COAG_SOURCE_EXPONENTIAL = 1, &
       COAG_SOURCE_LOGNORMAL = 2
  ! Langevin batches and first hits
  integer(c_int32_t), parameter :: COAG_WALL_SPECULAR = 0, COAG_WALL_ABSORBING = 1
  integer(c_int32_t), parameter :: COAG_BOUND_NONE = 0, COAG_BOUND_CLAMP = 1, COAG_BOUND_REFLECT = 2
  integer(c_int32_t), parameter :: COAG_DRIFT_ZERO = 0, COAG_DRIFT_FRICTION = 1, &
       COAG_DRIFT_MAFTEI2016 = 2, COAG_DRIFT_CALLBACK = 3
  ! the registry: coag_scheme_info%model, %inits (bits), %sizes, %memory, %law
  integer(c_int32_t), parameter :: COAG_MODEL_COAGULATION = 0, COAG_MODEL_TEMPERATURE = 1, COAG_MODEL_GAS = 2
  integer(c_int32_t), parameter :: COAG_INIT_COUNTS = 1, COAG_INIT_SIZES = 2, COAG_INIT_TEMPERATURES = 4, &
       COAG_INIT_VELOCITIES = 8
  integer(c_int32_t), parameter :: COAG_SAMPLES_NONE = 0, COAG_SAMPLES_MASS = 1, COAG_SAMPLES_NUMBER = 2
  integer(c_int32_t), parameter :: COAG_MEMORY_FIXED = 0, COAG_MEMORY_GROWING = 1
  integer(c_int32_t), parameter :: COAG_LAW_FINITE_N = 0, COAG_LAW_MASS_FLOW = 1, COAG_LAW_TIME_STEPPED = 2, &
       COAG_LAW_TEMPERATURE = 3, COAG_LAW_GAS = 4
  ! coag_option_info%kind (C's COAG_OPTION_COUNT is COAG_OPTION_KIND_COUNT here: Fortran names
  ! ignore case, and it would be the function coag_option_count); coag_builtin_info%family
  integer(c_int32_t), parameter :: COAG_OPTION_REAL = 0, COAG_OPTION_KIND_COUNT = 1, COAG_OPTION_FLAG = 2, &
       COAG_OPTION_NAME = 3
  integer(c_int32_t), parameter :: COAG_FAMILY_COAGULATION = 0, COAG_FAMILY_TEMPERATURE = 1, COAG_FAMILY_GAS = 2

  ! a user coagulation kernel (unused bounds c_null_funptr, rank 0)
  type, bind(c) :: coag_user_kernel
     type(c_funptr) :: rate, majorant
     integer(c_int32_t) :: rank                ! uint32_t, at most 8
     type(c_funptr) :: factors
     integer(c_int32_t) :: low_rank_exact
     type(c_funptr) :: sup
     type(c_ptr) :: user_data
  end type coag_user_kernel

  ! a user fragmentation kernel
  type, bind(c) :: coag_user_fragmentation
     type(c_funptr) :: rate, inverse_piece
     real(c_double) :: sup_rate
     type(c_ptr) :: user_data
  end type coag_user_fragmentation

  ! a Langevin batch's configuration: fill with coag_langevin_default_config
  type, bind(c) :: coag_langevin_config
     integer(c_size_t) :: struct_size
     integer(c_int32_t) :: dim                 ! uint32_t
     integer(c_int32_t) :: wall
     real(c_double) :: dt, sigma, radius, period
     integer(c_int32_t) :: bound_kind
     real(c_double) :: bound
     integer(c_int32_t) :: drift
     real(c_double) :: friction_rate
     type(c_funptr) :: drift_fn
     type(c_ptr) :: drift_user_data
  end type coag_langevin_config

  ! what one advance did, or the totals: set struct_size or call coag_step_report_init
  type, bind(c) :: coag_step_report
     integer(c_size_t) :: struct_size
     real(c_double) :: time
     integer(c_int64_t) :: events, proposals, rejections, bound_violations, clipped, doublings, &
          removed, bounces                     ! uint64_t
  end type coag_step_report

  ! the books of a sim's processes: set struct_size = c_sizeof(it)
  type, bind(c) :: coag_books
     integer(c_size_t) :: struct_size
     integer(c_int64_t) :: initial_number      ! uint64_t
     real(c_double) :: initial_mass
     integer(c_int64_t) :: injected_number     ! uint64_t
     real(c_double) :: injected_mass
     integer(c_int64_t) :: removed_number      ! uint64_t
     real(c_double) :: removed_mass, grown_mass
     integer(c_int64_t) :: merged, doublings   ! uint64_t
  end type coag_books

  ! a first-hit kernel estimation: set struct_size = c_sizeof(it)
  type, bind(c) :: coag_first_hits
     integer(c_size_t) :: struct_size
     integer(c_int32_t) :: dim                 ! uint32_t
     real(c_double) :: radius, outer, from, to, dt, sigma, velocity_sd
     integer(c_int64_t) :: trajectories        ! uint64_t
     integer(c_int32_t) :: drift
     real(c_double) :: friction_rate
     type(c_funptr) :: drift_fn
     type(c_ptr) :: drift_user_data
     integer(c_int64_t) :: work_limit          ! uint64_t, trajectory steps (0: none)
     type(c_funptr) :: cancel
     type(c_ptr) :: cancel_user_data
  end type coag_first_hits

  ! a registry scheme's capabilities (strings: static const char *, see coag_string)
  type, bind(c) :: coag_scheme_info
     integer(c_size_t) :: struct_size
     type(c_ptr) :: name, paper, summary
     integer(c_int32_t) :: model
     integer(c_int32_t) :: inits               ! uint32_t, COAG_INIT_* bits
     integer(c_int32_t) :: sizes, fragmentation, memory, law
     integer(c_int64_t) :: tag                 ! uint64_t
     integer(c_size_t) :: option_count, observable_count
  end type coag_scheme_info

  ! an option key's description
  type, bind(c) :: coag_option_info
     integer(c_size_t) :: struct_size
     type(c_ptr) :: name
     integer(c_int32_t) :: kind, must_match
     type(c_ptr) :: default_value, doc
  end type coag_option_info

  ! a built-in kernel of core's table
  type, bind(c) :: coag_builtin_info
     integer(c_size_t) :: struct_size
     type(c_ptr) :: name
     integer(c_int32_t) :: family
     type(c_ptr) :: formula, source, units
     integer(c_size_t) :: param_count
  end type coag_builtin_info

  ! a built-in kernel's parameter
  type, bind(c) :: coag_param_info
     integer(c_size_t) :: struct_size
     type(c_ptr) :: name
     integer(c_int32_t) :: has_default
     real(c_double) :: default_value           ! NaN when required
     type(c_ptr) :: unit, doc
  end type coag_param_info

  ! the callbacks' signatures (C typedefs of the same names)
  abstract interface
     real(c_double) function coag_rate_fn(x, y, user_data) bind(c)
       import
       real(c_double), value :: x, y
       type(c_ptr), value :: user_data
     end function
     real(c_double) function coag_unary_fn(x, user_data) bind(c)
       import
       real(c_double), value :: x
       type(c_ptr), value :: user_data
     end function
     subroutine coag_factors_fn(x, a, b, user_data) bind(c)   ! a(k), b(k), k <= rank
       import
       real(c_double), value :: x
       real(c_double), intent(out) :: a(*), b(*)
       type(c_ptr), value :: user_data
     end subroutine
     real(c_double) function coag_sup_fn(lo, hi, user_data) bind(c)
       import
       real(c_double), value :: lo, hi
       type(c_ptr), value :: user_data
     end function
     real(c_double) function coag_piece_fn(x, u, user_data) bind(c)
       import
       real(c_double), value :: x, u
       type(c_ptr), value :: user_data
     end function
     integer(c_int32_t) function coag_drift_fn(t, x, u, dim, out, user_data) bind(c)   ! 0: ok
       import
       real(c_double), value :: t
       real(c_double), intent(in) :: x(*), u(*)
       integer(c_size_t), value :: dim
       real(c_double), intent(out) :: out(*)
       type(c_ptr), value :: user_data
     end function
     integer(c_int32_t) function coag_cancel_callback(user_data) bind(c)   ! non-zero cancels
       import
       type(c_ptr), value :: user_data
     end function
     real(c_double) function coag_observable_fn(x, u, dim, user_data) bind(c)
       import
       real(c_double), intent(in) :: x(*), u(*)
       integer(c_size_t), value :: dim
       type(c_ptr), value :: user_data
     end function
     integer(c_int64_t) function coag_rng_callback(user_data) bind(c)   ! 64 random bits
       import
       type(c_ptr), value :: user_data
     end function
  end interface

end module coagula_types
