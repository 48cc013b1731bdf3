! coagula.f90 — Fortran 2008 (ISO_C_BINDING) interface to libcoagula: one interface per
! function of include/coagula.h, with the same name, argument order and types.
!
! Handles (coag_kernel, coag_fragmentation, coag_options, coag_sim, coag_langevin) are
! type(c_ptr); every function but the *_free subroutines, coag_version and
! coag_status_name returns an integer(c_int32_t) status (COAG_OK = 0), outputs written
! only on success. Strings passed in are NUL-terminated: "lowrank"//c_null_char.
! Strings coming out (const char *) are type(c_ptr): coag_string() copies one into a
! Fortran string; coag_error_message() returns the last error's message.
! Pointers the header lets be NULL (optional outputs and inputs: a step report, a
! fragmentation, options, the out pointers of coag_*_info, coag_*_state, ...) are
! type(c_ptr), value: pass c_loc(variable) (with the target attribute) or c_null_ptr.
! Required pointers are typed and passed by reference. C's unsigned integers
! (uint32_t, uint64_t) are the signed Fortran kinds of the same size; size_t is
! integer(c_size_t). Callbacks are bind(c) procedures passed with c_funloc (the abstract
! interfaces below give their signatures) or c_null_funptr. Structs are bind(c) derived
! types with the C field order; set struct_size = c_sizeof(it) (or fill it with the
! library's *_init / *_default_config / *_get).
module coagula
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

  interface
     ! ------------------------------------------------------------ exact solutions
     integer(c_int32_t) function coag_exact_moment(solution, m, t, out) bind(c, name="coag_exact_moment")
       import
       integer(c_int32_t), value :: solution, m   ! m: uint32_t
       real(c_double), value :: t
       real(c_double), intent(out) :: out
     end function
     integer(c_int32_t) function coag_exact_density(solution, k, t, out) bind(c, name="coag_exact_density")
       import
       integer(c_int32_t), value :: solution
       integer(c_int64_t), value :: k
       real(c_double), value :: t
       real(c_double), intent(out) :: out
     end function
     ! ------------------------------------------------------------ kernels, fragmentation
     integer(c_int32_t) function coag_kernel_new(name, params, n, out) bind(c, name="coag_kernel_new")
       import
       character(kind=c_char), intent(in) :: name(*)
       real(c_double), intent(in) :: params(*)
       integer(c_size_t), value :: n
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_kernel_new_user(desc, out) bind(c, name="coag_kernel_new_user")
       import
       type(coag_user_kernel), intent(in) :: desc
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_kernel_rate(kernel, x, y, out) bind(c, name="coag_kernel_rate")
       import
       type(c_ptr), value :: kernel
       real(c_double), value :: x, y
       real(c_double), intent(out) :: out
     end function
     subroutine coag_kernel_free(kernel) bind(c, name="coag_kernel_free")
       import
       type(c_ptr), value :: kernel
     end subroutine
     integer(c_int32_t) function coag_fragmentation_new_binary_uniform(lambda, out) &
          bind(c, name="coag_fragmentation_new_binary_uniform")
       import
       real(c_double), value :: lambda
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_fragmentation_new_user(desc, out) bind(c, name="coag_fragmentation_new_user")
       import
       type(coag_user_fragmentation), intent(in) :: desc
       type(c_ptr), intent(out) :: out
     end function
     subroutine coag_fragmentation_free(frag) bind(c, name="coag_fragmentation_free")
       import
       type(c_ptr), value :: frag
     end subroutine
     ! ------------------------------------------------------------ Langevin batches
     integer(c_int32_t) function coag_langevin_default_config(out, size) bind(c, name="coag_langevin_default_config")
       import
       type(coag_langevin_config), intent(out) :: out
       integer(c_size_t), value :: size
     end function
     integer(c_int32_t) function coag_langevin_new(config, n, x0, u0, seed, first_id, out) &
          bind(c, name="coag_langevin_new")
       import
       type(coag_langevin_config), intent(in) :: config
       integer(c_int64_t), value :: n, seed, first_id
       real(c_double), intent(in) :: x0(*), u0(*)
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_langevin_workspace_size(config, n, out) bind(c, name="coag_langevin_workspace_size")
       import
       type(coag_langevin_config), intent(in) :: config
       integer(c_int64_t), value :: n
       integer(c_size_t), intent(out) :: out
     end function
     ! workspace: c_loc of a real(c_double) array kept alive until coag_langevin_free
     integer(c_int32_t) function coag_langevin_new_in(config, n, x0, u0, seed, first_id, workspace, workspace_bytes, &
          out) bind(c, name="coag_langevin_new_in")
       import
       type(coag_langevin_config), intent(in) :: config
       integer(c_int64_t), value :: n, seed, first_id
       real(c_double), intent(in) :: x0(*), u0(*)
       type(c_ptr), value :: workspace
       integer(c_size_t), value :: workspace_bytes
       type(c_ptr), intent(out) :: out
     end function
     subroutine coag_langevin_free(h) bind(c, name="coag_langevin_free")
       import
       type(c_ptr), value :: h
     end subroutine
     integer(c_int32_t) function coag_langevin_advance_to(h, t, report) bind(c, name="coag_langevin_advance_to")
       import
       type(c_ptr), value :: h
       real(c_double), value :: t
       type(c_ptr), value :: report               ! coag_step_report or NULL
     end function
     integer(c_int32_t) function coag_langevin_set_work_limit(h, units) bind(c, name="coag_langevin_set_work_limit")
       import
       type(c_ptr), value :: h
       integer(c_int64_t), value :: units
     end function
     integer(c_int32_t) function coag_langevin_set_cancel_callback(h, cancel, user_data) &
          bind(c, name="coag_langevin_set_cancel_callback")
       import
       type(c_ptr), value :: h, user_data
       type(c_funptr), value :: cancel             ! coag_cancel_callback or NULL
     end function
     integer(c_int32_t) function coag_langevin_clone(h, out) bind(c, name="coag_langevin_clone")
       import
       type(c_ptr), value :: h
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_first_hit_kernel(p, seed, first_id, mean, std_error, hits) &
          bind(c, name="coag_first_hit_kernel")
       import
       type(coag_first_hits), intent(in) :: p
       integer(c_int64_t), value :: seed, first_id
       real(c_double), intent(out) :: mean, std_error
       type(c_ptr), value :: hits                  ! uint64_t or NULL
     end function
     integer(c_int32_t) function coag_langevin_info(h, time, dim, n) bind(c, name="coag_langevin_info")
       import
       type(c_ptr), value :: h, time, dim, n       ! double, size_t, uint64_t; each may be NULL
     end function
     ! x, u: n*dim doubles (trajectory-major); hits: n uint64_t; first_hit: n doubles; each may be NULL
     integer(c_int32_t) function coag_langevin_state(h, x, u, hits, first_hit, len) bind(c, name="coag_langevin_state")
       import
       type(c_ptr), value :: h, x, u, hits, first_hit
       integer(c_size_t), value :: len
     end function
     integer(c_int32_t) function coag_langevin_mean(h, f, user_data, mean, std_error, absorbed) &
          bind(c, name="coag_langevin_mean")
       import
       type(c_ptr), value :: h, user_data
       type(c_funptr), value :: f                  ! coag_observable_fn, or NULL: hits per trajectory
       real(c_double), intent(out) :: mean, std_error
       type(c_ptr), value :: absorbed              ! uint64_t or NULL
     end function
     integer(c_int32_t) function coag_langevin_checkpoint_size(h, out) bind(c, name="coag_langevin_checkpoint_size")
       import
       type(c_ptr), value :: h
       integer(c_size_t), intent(out) :: out
     end function
     integer(c_int32_t) function coag_langevin_save(h, buf, len, written) bind(c, name="coag_langevin_save")
       import
       type(c_ptr), value :: h
       integer(c_int8_t), intent(inout) :: buf(*)
       integer(c_size_t), value :: len
       type(c_ptr), value :: written               ! size_t or NULL
     end function
     integer(c_int32_t) function coag_langevin_restore(h, buf, len) bind(c, name="coag_langevin_restore")
       import
       type(c_ptr), value :: h
       integer(c_int8_t), intent(in) :: buf(*)
       integer(c_size_t), value :: len
     end function
     ! ------------------------------------------------------------ options
     integer(c_int32_t) function coag_options_new(out) bind(c, name="coag_options_new")
       import
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_options_clone(options, out) bind(c, name="coag_options_clone")
       import
       type(c_ptr), value :: options
       type(c_ptr), intent(out) :: out
     end function
     subroutine coag_options_free(options) bind(c, name="coag_options_free")
       import
       type(c_ptr), value :: options
     end subroutine
     integer(c_int32_t) function coag_options_set_real(options, key, value) bind(c, name="coag_options_set_real")
       import
       type(c_ptr), value :: options
       character(kind=c_char), intent(in) :: key(*)
       real(c_double), value :: value
     end function
     integer(c_int32_t) function coag_options_set_count(options, key, value) bind(c, name="coag_options_set_count")
       import
       type(c_ptr), value :: options
       character(kind=c_char), intent(in) :: key(*)
       integer(c_int64_t), value :: value
     end function
     integer(c_int32_t) function coag_options_set_flag(options, key, value) bind(c, name="coag_options_set_flag")
       import
       type(c_ptr), value :: options
       character(kind=c_char), intent(in) :: key(*)
       integer(c_int32_t), value :: value
     end function
     integer(c_int32_t) function coag_options_set_name(options, key, value) bind(c, name="coag_options_set_name")
       import
       type(c_ptr), value :: options
       character(kind=c_char), intent(in) :: key(*), value(*)
     end function
     ! ------------------------------------------------------------ the registry and core's tables
     integer(c_int32_t) function coag_scheme_count(out) bind(c, name="coag_scheme_count")
       import
       integer(c_size_t), intent(out) :: out
     end function
     integer(c_int32_t) function coag_scheme_find(name, out) bind(c, name="coag_scheme_find")
       import
       character(kind=c_char), intent(in) :: name(*)
       integer(c_size_t), intent(out) :: out
     end function
     integer(c_int32_t) function coag_scheme_info_get(index, out, size) bind(c, name="coag_scheme_info_get")
       import
       integer(c_size_t), value :: index, size
       type(coag_scheme_info), intent(out) :: out
     end function
     integer(c_int32_t) function coag_scheme_option(index, i, out) bind(c, name="coag_scheme_option")
       import
       integer(c_size_t), value :: index, i
       type(c_ptr), intent(out) :: out             ! const char *
     end function
     integer(c_int32_t) function coag_scheme_observable(index, i, out) bind(c, name="coag_scheme_observable")
       import
       integer(c_size_t), value :: index, i
       type(c_ptr), intent(out) :: out             ! const char *
     end function
     integer(c_int32_t) function coag_option_count(out) bind(c, name="coag_option_count")
       import
       integer(c_size_t), intent(out) :: out
     end function
     integer(c_int32_t) function coag_option_info_get(index, out, size) bind(c, name="coag_option_info_get")
       import
       integer(c_size_t), value :: index, size
       type(coag_option_info), intent(out) :: out
     end function
     integer(c_int32_t) function coag_builtin_count(out) bind(c, name="coag_builtin_count")
       import
       integer(c_size_t), intent(out) :: out
     end function
     integer(c_int32_t) function coag_builtin_info_get(index, out, size) bind(c, name="coag_builtin_info_get")
       import
       integer(c_size_t), value :: index, size
       type(coag_builtin_info), intent(out) :: out
     end function
     integer(c_int32_t) function coag_builtin_param(index, param, out, size) bind(c, name="coag_builtin_param")
       import
       integer(c_size_t), value :: index, param, size
       type(coag_param_info), intent(out) :: out
     end function
     integer(c_int32_t) function coag_step_report_init(out, size) bind(c, name="coag_step_report_init")
       import
       type(coag_step_report), intent(out) :: out
       integer(c_size_t), value :: size
     end function
     ! ------------------------------------------------------------ sims: construction
     ! kernel: a handle; frag, options: handles or c_null_ptr (none, every default)
     integer(c_int32_t) function coag_sim_new_counts(scheme, kernel, frag, options, counts, len, volume, out) &
          bind(c, name="coag_sim_new_counts")
       import
       character(kind=c_char), intent(in) :: scheme(*)
       type(c_ptr), value :: kernel, frag, options
       integer(c_int64_t), intent(in) :: counts(*)
       integer(c_size_t), value :: len
       real(c_double), value :: volume
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_new_sizes(scheme, kernel, frag, options, sizes, n, mass, out) &
          bind(c, name="coag_sim_new_sizes")
       import
       character(kind=c_char), intent(in) :: scheme(*)
       type(c_ptr), value :: kernel, frag, options
       real(c_double), intent(in) :: sizes(*)
       integer(c_size_t), value :: n
       real(c_double), value :: mass
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_workspace_size(scheme, frag, options, n, out) &
          bind(c, name="coag_sim_workspace_size")
       import
       character(kind=c_char), intent(in) :: scheme(*)
       type(c_ptr), value :: frag, options
       integer(c_size_t), value :: n
       integer(c_size_t), intent(out) :: out
     end function
     ! workspace: c_loc of a real(c_double) array kept alive until coag_sim_free
     integer(c_int32_t) function coag_sim_new_sizes_in(scheme, kernel, frag, options, sizes, n, mass, workspace, &
          workspace_bytes_given, out) bind(c, name="coag_sim_new_sizes_in")
       import
       character(kind=c_char), intent(in) :: scheme(*)
       type(c_ptr), value :: kernel, frag, options
       real(c_double), intent(in) :: sizes(*)
       integer(c_size_t), value :: n
       real(c_double), value :: mass
       type(c_ptr), value :: workspace
       integer(c_size_t), value :: workspace_bytes_given
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_new_temperatures(scheme, kernel, options, counts, temperatures, len, &
          volume, out) bind(c, name="coag_sim_new_temperatures")
       import
       character(kind=c_char), intent(in) :: scheme(*)
       type(c_ptr), value :: kernel, options
       integer(c_int64_t), intent(in) :: counts(*)
       real(c_double), intent(in) :: temperatures(*)
       integer(c_size_t), value :: len
       real(c_double), value :: volume
       type(c_ptr), intent(out) :: out
     end function
     ! velocities(3*n): particle p's velocity in velocities(3p-2:3p)
     integer(c_int32_t) function coag_sim_new_velocities(scheme, kernel, options, sizes, velocities, n, volume, out) &
          bind(c, name="coag_sim_new_velocities")
       import
       character(kind=c_char), intent(in) :: scheme(*)
       type(c_ptr), value :: kernel, options
       integer(c_int64_t), intent(in) :: sizes(*)
       real(c_double), intent(in) :: velocities(*)
       integer(c_size_t), value :: n
       real(c_double), value :: volume
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_new_maxwellian(scheme, kernel, options, counts, temperatures, len, &
          volume, out) bind(c, name="coag_sim_new_maxwellian")
       import
       character(kind=c_char), intent(in) :: scheme(*)
       type(c_ptr), value :: kernel, options
       integer(c_int64_t), intent(in) :: counts(*)
       real(c_double), intent(in) :: temperatures(*)
       integer(c_size_t), value :: len
       real(c_double), value :: volume
       type(c_ptr), intent(out) :: out
     end function
     subroutine coag_sim_free(sim) bind(c, name="coag_sim_free")
       import
       type(c_ptr), value :: sim
     end subroutine
     integer(c_int32_t) function coag_sim_clone(sim, out) bind(c, name="coag_sim_clone")
       import
       type(c_ptr), value :: sim
       type(c_ptr), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_scheme(sim, out) bind(c, name="coag_sim_scheme")
       import
       type(c_ptr), value :: sim
       type(c_ptr), intent(out) :: out             ! const char *
     end function
     integer(c_int32_t) function coag_sim_engine(sim, out) bind(c, name="coag_sim_engine")
       import
       type(c_ptr), value :: sim
       type(c_ptr), intent(out) :: out             ! const char *
     end function
     ! ------------------------------------------------------------ sims: stepping
     integer(c_int32_t) function coag_sim_advance_to(sim, t, report) bind(c, name="coag_sim_advance_to")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: t
       type(c_ptr), value :: report               ! coag_step_report or NULL
     end function
     integer(c_int32_t) function coag_sim_set_work_limit(sim, units) bind(c, name="coag_sim_set_work_limit")
       import
       type(c_ptr), value :: sim
       integer(c_int64_t), value :: units
     end function
     integer(c_int32_t) function coag_sim_set_cancel_callback(sim, cancel, user_data) &
          bind(c, name="coag_sim_set_cancel_callback")
       import
       type(c_ptr), value :: sim, user_data
       type(c_funptr), value :: cancel             ! coag_cancel_callback or NULL
     end function
     integer(c_int32_t) function coag_sim_set_rng_callback(sim, next, user_data) bind(c, name="coag_sim_set_rng_callback")
       import
       type(c_ptr), value :: sim, user_data
       type(c_funptr), value :: next               ! coag_rng_callback or NULL
     end function
     integer(c_int32_t) function coag_sim_reseed(sim, seed, stream) bind(c, name="coag_sim_reseed")
       import
       type(c_ptr), value :: sim
       integer(c_int64_t), value :: seed, stream
     end function
     ! ------------------------------------------------------------ sims: checkpoints
     integer(c_int32_t) function coag_sim_checkpoint_size(sim, out) bind(c, name="coag_sim_checkpoint_size")
       import
       type(c_ptr), value :: sim
       integer(c_size_t), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_checkpoint(sim, buf, len, written) bind(c, name="coag_sim_checkpoint")
       import
       type(c_ptr), value :: sim
       integer(c_int8_t), intent(inout) :: buf(*)
       integer(c_size_t), value :: len
       type(c_ptr), value :: written               ! size_t or NULL
     end function
     integer(c_int32_t) function coag_sim_restore(sim, buf, len) bind(c, name="coag_sim_restore")
       import
       type(c_ptr), value :: sim
       integer(c_int8_t), intent(in) :: buf(*)
       integer(c_size_t), value :: len
     end function
     ! ------------------------------------------------------------ sims: reading
     integer(c_int32_t) function coag_sim_time(sim, out) bind(c, name="coag_sim_time")
       import
       type(c_ptr), value :: sim
       real(c_double), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_totals(sim, out) bind(c, name="coag_sim_totals")
       import
       type(c_ptr), value :: sim
       type(coag_step_report), intent(inout) :: out   ! struct_size set
     end function
     integer(c_int32_t) function coag_sim_moment(sim, m, out) bind(c, name="coag_sim_moment")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: m
       real(c_double), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_concentration(sim, a, b, out) bind(c, name="coag_sim_concentration")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: a, b
       real(c_double), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_class_concentrations(sim, edges, n_edges, out) &
         bind(c, name="coag_sim_class_concentrations")
       import
       type(c_ptr), value :: sim
       real(c_double), intent(in) :: edges(*)
       integer(c_size_t), value :: n_edges
       real(c_double), intent(out) :: out(*)   ! n_edges - 1 values
     end function
     integer(c_int32_t) function coag_sim_gel_mass(sim, out) bind(c, name="coag_sim_gel_mass")
       import
       type(c_ptr), value :: sim
       real(c_double), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_particle_count(sim, out) bind(c, name="coag_sim_particle_count")
       import
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(out) :: out      ! uint64_t
     end function
     integer(c_int32_t) function coag_sim_state_len(sim, out) bind(c, name="coag_sim_state_len")
       import
       type(c_ptr), value :: sim
       integer(c_size_t), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_occupied(sim, out) bind(c, name="coag_sim_occupied")
       import
       type(c_ptr), value :: sim
       integer(c_size_t), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_get_pairs(sim, sizes, counts, len, volume, written) &
          bind(c, name="coag_sim_get_pairs")
       import
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(inout) :: sizes(*), counts(*)
       integer(c_size_t), value :: len
       type(c_ptr), value :: volume, written       ! double, size_t; each may be NULL
     end function
     integer(c_int32_t) function coag_sim_get_sizes(sim, buf, len) bind(c, name="coag_sim_get_sizes")
       import
       type(c_ptr), value :: sim
       real(c_double), intent(inout) :: buf(*)
       integer(c_size_t), value :: len
     end function
     integer(c_int32_t) function coag_sim_get_counts(sim, buf, len, volume) bind(c, name="coag_sim_get_counts")
       import
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(inout) :: buf(*)
       integer(c_size_t), value :: len
       type(c_ptr), value :: volume                ! double or NULL
     end function
     integer(c_int32_t) function coag_sim_observable(sim, name, out) bind(c, name="coag_sim_observable")
       import
       type(c_ptr), value :: sim
       character(kind=c_char), intent(in) :: name(*)
       real(c_double), intent(out) :: out
     end function
     integer(c_int32_t) function coag_sim_size_values(sim, name, sizes, values, len, written) &
          bind(c, name="coag_sim_size_values")
       import
       type(c_ptr), value :: sim
       character(kind=c_char), intent(in) :: name(*)
       integer(c_int64_t), intent(inout) :: sizes(*)
       real(c_double), intent(inout) :: values(*)
       integer(c_size_t), value :: len
       type(c_ptr), value :: written               ! size_t or NULL
     end function
     ! velocities(3*len): particle p's velocity in velocities(3p-2:3p)
     integer(c_int32_t) function coag_sim_velocities(sim, sizes, velocities, len) bind(c, name="coag_sim_velocities")
       import
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(inout) :: sizes(*)
       real(c_double), intent(inout) :: velocities(*)
       integer(c_size_t), value :: len
     end function
     ! ------------------------------------------------------------ sims: what a host changes
     integer(c_int32_t) function coag_sim_set_pairs(sim, sizes, counts, len, volume) bind(c, name="coag_sim_set_pairs")
       import
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(in) :: sizes(*), counts(*)
       integer(c_size_t), value :: len
       real(c_double), value :: volume
     end function
     integer(c_int32_t) function coag_sim_set_sizes(sim, sizes, len) bind(c, name="coag_sim_set_sizes")
       import
       type(c_ptr), value :: sim
       real(c_double), intent(in) :: sizes(*)
       integer(c_size_t), value :: len
     end function
     integer(c_int32_t) function coag_sim_set_counts(sim, counts, len, volume) bind(c, name="coag_sim_set_counts")
       import
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(in) :: counts(*)
       integer(c_size_t), value :: len
       real(c_double), value :: volume
     end function
     integer(c_int32_t) function coag_sim_set_kernel(sim, kernel) bind(c, name="coag_sim_set_kernel")
       import
       type(c_ptr), value :: sim, kernel
     end function
     integer(c_int32_t) function coag_sim_set_fragmentation(sim, frag) bind(c, name="coag_sim_set_fragmentation")
       import
       type(c_ptr), value :: sim, frag             ! frag: a handle or NULL (none)
     end function
     integer(c_int32_t) function coag_sim_set_dt(sim, dt) bind(c, name="coag_sim_set_dt")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: dt
     end function
     integer(c_int32_t) function coag_sim_set_time(sim, t) bind(c, name="coag_sim_set_time")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: t
     end function
     integer(c_int32_t) function coag_sim_set_mass(sim, mass) bind(c, name="coag_sim_set_mass")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: mass
     end function
     integer(c_int32_t) function coag_sim_set_source(sim, rate, kind, p1, p2) bind(c, name="coag_sim_set_source")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: rate
       integer(c_int32_t), value :: kind          ! COAG_SOURCE_*
       real(c_double), value :: p1, p2
     end function
     integer(c_int32_t) function coag_sim_set_removal(sim, coefficient, exponent) bind(c, name="coag_sim_set_removal")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: coefficient, exponent
     end function
     integer(c_int32_t) function coag_sim_set_growth(sim, coefficient, exponent) bind(c, name="coag_sim_set_growth")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: coefficient, exponent
     end function
     integer(c_int32_t) function coag_sim_clear_processes(sim) bind(c, name="coag_sim_clear_processes")
       import
       type(c_ptr), value :: sim
     end function
     integer(c_int32_t) function coag_sim_books(sim, out) bind(c, name="coag_sim_books")
       import
       type(c_ptr), value :: sim
       type(coag_books), intent(inout) :: out     ! struct_size set
     end function
     ! ------------------------------------------------------------ the library
     type(c_ptr) function coag_version() bind(c, name="coag_version")
       import
     end function
     type(c_ptr) function coag_status_name(status) bind(c, name="coag_status_name")
       import
       integer(c_int32_t), value :: status
     end function
     ! buf: c_loc of a character(kind=c_char) array of buf_len, or c_null_ptr with buf_len 0
     integer(c_int32_t) function coag_last_error_message(buf, buf_len, out_len) bind(c, name="coag_last_error_message")
       import
       type(c_ptr), value :: buf, out_len          ! out_len: size_t or NULL
       integer(c_size_t), value :: buf_len
     end function
  end interface

contains

  !> A copy of the NUL-terminated C string `p` (a static name, version, message).
  function coag_string(p) result(s)
    type(c_ptr), intent(in) :: p
    character(len=:), allocatable :: s
    character(kind=c_char), pointer :: c(:)
    integer :: n
    if (.not. c_associated(p)) then
       s = ""
       return
    end if
    call c_f_pointer(p, c, [huge(0)])
    n = 0
    do while (c(n + 1) /= c_null_char)
       n = n + 1
    end do
    allocate(character(len=n) :: s)
    s = transfer(c(1:n), s)
  end function coag_string

  !> The message of the last failed call on this thread.
  function coag_error_message() result(msg)
    character(len=:), allocatable :: msg
    character(kind=c_char), allocatable, target :: buf(:)
    integer(c_size_t), target :: n
    n = 0
    if (coag_last_error_message(c_null_ptr, 0_c_size_t, c_loc(n)) == COAG_NULL_PARAMETER .or. n == 0) then
       msg = ""
       return
    end if
    allocate(buf(n + 1))
    if (coag_last_error_message(c_loc(buf), n + 1, c_null_ptr) /= COAG_OK) then
       msg = ""
       return
    end if
    msg = coag_string(c_loc(buf))
  end function coag_error_message

end module coagula
