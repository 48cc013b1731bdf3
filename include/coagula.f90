! coagula.f90 — Fortran 2003 (ISO_C_BINDING) interface to libcoagula.
!
! Handles are type(c_ptr); every function returns an integer(c_int32_t) status
! (COAG_OK = 0). Sizes and counts are passed as arrays with their lengths
! (integer(c_size_t)). Conventions as in coagula.h: outputs are written only on
! success, a failed call leaves the handle usable, one thread at a time per handle.
! coag_error_message() returns the last error as a Fortran string.
module coagula
  use, intrinsic :: iso_c_binding
  implicit none
  private :: c_strlen_like

  integer(c_int32_t), parameter :: COAG_OK = 0, COAG_NULL_PARAMETER = 1, &
       COAG_INVALID_ARGUMENT = 2, COAG_BUFFER_TOO_SMALL = 3, COAG_CAPACITY = 4, &
       COAG_INVALID_RATE = 5, COAG_UNSUPPORTED = 6, COAG_TIME_BACKWARDS = 7, &
       COAG_BAD_CHECKPOINT = 8, COAG_PANIC = 9, COAG_INTERRUPTED = 10, COAG_RNG_FAILURE = 11
  integer(c_int32_t), parameter :: COAG_POINTS_NIEDERREITER = 0, COAG_POINTS_SOBOL = 1, &
       COAG_POINTS_MONTE_CARLO = 2
  integer(c_int32_t), parameter :: COAG_RANDOMIZATION_NONE = 0, COAG_RANDOMIZATION_SHIFT = 1, &
       COAG_RANDOMIZATION_MATOUSEK = 2, COAG_RANDOMIZATION_OWEN = 3
  integer(c_int32_t), parameter :: COAG_METHOD_LOWRANK = 0, COAG_METHOD_INVERSE = 1, &
       COAG_METHOD_REJECTION = 2, COAG_METHOD_LOWRANK_TREE = 3, COAG_METHOD_DSA_COUNTS = 4
  integer(c_int32_t), parameter :: COAG_BUCKET_AUTO = 0, COAG_BUCKET_SLOTS = 1, &
       COAG_BUCKET_COUNTED = 2
  integer(c_int32_t), parameter :: COAG_EVENTFLOW_MFA = 0, COAG_EVENTFLOW_DSA = 1, &
       COAG_EVENTFLOW_LOWRANK = 2
  integer(c_int32_t), parameter :: COAG_SAMPLER_DEFAULT = 0, COAG_SAMPLER_TREE = 1, &
       COAG_SAMPLER_GROUPS = 2
  integer(c_int32_t), parameter :: COAG_EXACT_CONSTANT = 0, COAG_EXACT_ADDITIVE = 1, &
       COAG_EXACT_MULTIPLICATIVE = 2, COAG_EXACT_MARCUS_LUSHNIKOV = 3, COAG_EXACT_COAG_FRAG = 4

  integer(c_int32_t), parameter :: COAG_WALL_SPECULAR = 0, COAG_WALL_ABSORBING = 1
  integer(c_int32_t), parameter :: COAG_BOUND_NONE = 0, COAG_BOUND_CLAMP = 1, COAG_BOUND_REFLECT = 2
  integer(c_int32_t), parameter :: COAG_DRIFT_ZERO = 0, COAG_DRIFT_FRICTION = 1, &
       COAG_DRIFT_MAFTEI2016 = 2, COAG_DRIFT_CALLBACK = 3

  ! Langevin batches (Maftei et al. 2016); fill with coag_langevin_default_config
  type, bind(c) :: coag_langevin_config
     integer(c_size_t) :: struct_size
     integer(c_int32_t) :: dim, wall
     real(c_double) :: dt, sigma, radius, period
     integer(c_int32_t) :: bound_kind
     real(c_double) :: bound
     integer(c_int32_t) :: drift
     real(c_double) :: friction_rate
     type(c_funptr) :: drift_fn
     type(c_ptr) :: drift_user_data
  end type coag_langevin_config

  ! temperature-dependent low-rank MC (Osinsky 2023 §4); fill with coag_thermal_default_config
  integer(c_int32_t), parameter :: COAG_THERMAL_BALLISTIC = 0, COAG_THERMAL_MODEL = 1
  integer(c_int32_t), parameter :: COAG_THERMAL_LOWRANK = 0, COAG_THERMAL_REJECTION = 1
  type, bind(c) :: coag_thermal_config
     integer(c_size_t) :: struct_size
     integer(c_int32_t) :: kernel, engine
     real(c_double) :: restitution, barrier, barrier_exponent, model_c, model_gamma
     integer(c_int64_t) :: size_limit, seed, stream
  end type coag_thermal_config

  ! low-rank DSMC (Osinsky 2023 §5); fill with coag_dsmc_default_config
  integer(c_int32_t), parameter :: COAG_DSMC_LOWRANK = 0, COAG_DSMC_REJECTION = 1
  type, bind(c) :: coag_dsmc_config
     integer(c_size_t) :: struct_size
     integer(c_int32_t) :: engine
     real(c_double) :: restitution, stick_speed
     integer(c_int64_t) :: seed, stream
  end type coag_dsmc_config

  ! a first-hit kernel estimation; set struct_size = c_sizeof(it)
  type, bind(c) :: coag_first_hits
     integer(c_size_t) :: struct_size
     integer(c_int32_t) :: dim
     real(c_double) :: radius, outer, from, to, dt, sigma, velocity_sd
     integer(c_int64_t) :: trajectories
     integer(c_int32_t) :: drift
     real(c_double) :: friction_rate
     type(c_funptr) :: drift_fn
     type(c_ptr) :: drift_user_data
  end type coag_first_hits

  type, bind(c) :: coag_massflow_config
     integer(c_size_t) :: struct_size
     real(c_double) :: dt
     real(c_double) :: mass
     integer(c_int32_t) :: points
     integer(c_int32_t) :: randomization
     integer(c_int32_t) :: full_sort
     integer(c_int64_t) :: seed
     integer(c_int64_t) :: stream
  end type coag_massflow_config

  type, bind(c) :: coag_counts_config
     integer(c_size_t) :: struct_size
     integer(c_int32_t) :: method
     real(c_double) :: volume
     integer(c_int64_t) :: size_limit
     integer(c_int64_t) :: memory_budget
     integer(c_int64_t) :: seed
     integer(c_int64_t) :: stream
     integer(c_int32_t) :: batched_clock
     integer(c_int32_t) :: reserved
     integer(c_int32_t) :: bucket_mode
  end type coag_counts_config

  type, bind(c) :: coag_eventflow_config
     integer(c_size_t) :: struct_size
     integer(c_int32_t) :: method
     real(c_double) :: mass
     real(c_double) :: truncation
     integer(c_int64_t) :: capacity
     integer(c_int32_t) :: sampler
     integer(c_int32_t) :: strict_bound
     integer(c_int64_t) :: seed
     integer(c_int64_t) :: stream
  end type coag_eventflow_config

  ! user kernels: procedures with bind(c) interfaces, passed with c_funloc
  type, bind(c) :: coag_user_kernel
     type(c_funptr) :: rate, majorant
     integer(c_int32_t) :: rank
     type(c_funptr) :: factors
     integer(c_int32_t) :: low_rank_exact
     type(c_funptr) :: sup
     type(c_ptr) :: user_data
  end type coag_user_kernel

  type, bind(c) :: coag_user_fragmentation
     type(c_funptr) :: rate, inverse_piece
     real(c_double) :: sup_rate
     type(c_ptr) :: user_data
  end type coag_user_fragmentation

  ! set struct_size = c_sizeof(report) before passing a report (or call
  ! coag_step_report_init)
  type, bind(c) :: coag_step_report
     integer(c_size_t) :: struct_size
     real(c_double) :: time
     integer(c_int64_t) :: events, proposals, rejections, bound_violations, clipped, doublings
     integer(c_int64_t) :: removed, bounces
  end type coag_step_report

  interface
     function coag_langevin_default_config(out, size) bind(c, name="coag_langevin_default_config")
       import :: coag_langevin_config, c_size_t, c_int32_t
       type(coag_langevin_config), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_langevin_default_config
     end function
     function coag_langevin_new(config, n, x0, u0, seed, first_id, out) bind(c, name="coag_langevin_new")
       import :: coag_langevin_config, c_int64_t, c_double, c_ptr, c_int32_t
       type(coag_langevin_config), intent(in) :: config
       integer(c_int64_t), value :: n
       real(c_double), intent(in) :: x0(*), u0(*)
       integer(c_int64_t), value :: seed, first_id
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_langevin_new
     end function
     function coag_langevin_workspace_size(config, n, out) bind(c, name="coag_langevin_workspace_size")
       import :: coag_langevin_config, c_int64_t, c_size_t, c_int32_t
       type(coag_langevin_config), intent(in) :: config
       integer(c_int64_t), value :: n
       integer(c_size_t), intent(out) :: out
       integer(c_int32_t) :: coag_langevin_workspace_size
     end function
     ! the workspace (c_loc of a real(c_double) array) must stay allocated until
     ! coag_langevin_free
     function coag_langevin_new_in(config, n, x0, u0, seed, first_id, workspace, workspace_bytes, out) &
          bind(c, name="coag_langevin_new_in")
       import :: coag_langevin_config, c_int64_t, c_double, c_ptr, c_size_t, c_int32_t
       type(coag_langevin_config), intent(in) :: config
       integer(c_int64_t), value :: n
       real(c_double), intent(in) :: x0(*), u0(*)
       integer(c_int64_t), value :: seed, first_id
       type(c_ptr), value :: workspace
       integer(c_size_t), value :: workspace_bytes
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_langevin_new_in
     end function
     subroutine coag_langevin_free(h) bind(c, name="coag_langevin_free")
       import :: c_ptr
       type(c_ptr), value :: h
     end subroutine
     function coag_langevin_advance_to(h, t, report) bind(c, name="coag_langevin_advance_to")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: h
       real(c_double), value :: t
       type(c_ptr), value :: report
       integer(c_int32_t) :: coag_langevin_advance_to
     end function
     ! time, dim, n: c_loc of the variables, or c_null_ptr
     function coag_langevin_info(h, time, dim, n) bind(c, name="coag_langevin_info")
       import :: c_ptr, c_int32_t
       type(c_ptr), value :: h, time, dim, n
       integer(c_int32_t) :: coag_langevin_info
     end function
     ! x, u (n*dim doubles), hits (n int64), first_hit (n doubles): c_loc or c_null_ptr
     function coag_langevin_state(h, x, u, hits, first_hit, len) bind(c, name="coag_langevin_state")
       import :: c_ptr, c_size_t, c_int32_t
       type(c_ptr), value :: h, x, u, hits, first_hit
       integer(c_size_t), value :: len
       integer(c_int32_t) :: coag_langevin_state
     end function
     ! f: c_funloc of a bind(c) function (x, u, dim, user_data) -> real(c_double), or
     ! c_null_funptr for the hits per trajectory; absorbed: c_loc or c_null_ptr
     function coag_langevin_mean(h, f, user_data, mean, std_error, absorbed) bind(c, name="coag_langevin_mean")
       import :: c_ptr, c_funptr, c_double, c_int32_t
       type(c_ptr), value :: h
       type(c_funptr), value :: f
       type(c_ptr), value :: user_data
       real(c_double), intent(out) :: mean, std_error
       type(c_ptr), value :: absorbed
       integer(c_int32_t) :: coag_langevin_mean
     end function
     function coag_langevin_checkpoint_size(h, out) bind(c, name="coag_langevin_checkpoint_size")
       import :: c_ptr, c_size_t, c_int32_t
       type(c_ptr), value :: h
       integer(c_size_t), intent(out) :: out
       integer(c_int32_t) :: coag_langevin_checkpoint_size
     end function
     function coag_langevin_save(h, buf, n, written) bind(c, name="coag_langevin_save")
       import :: c_ptr, c_int8_t, c_size_t, c_int32_t
       type(c_ptr), value :: h
       integer(c_int8_t), intent(out) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_size_t), intent(out) :: written
       integer(c_int32_t) :: coag_langevin_save
     end function
     function coag_langevin_restore(h, buf, n) bind(c, name="coag_langevin_restore")
       import :: c_ptr, c_int8_t, c_size_t, c_int32_t
       type(c_ptr), value :: h
       integer(c_int8_t), intent(in) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_int32_t) :: coag_langevin_restore
     end function
     function coag_first_hit_kernel(p, seed, first_id, mean, std_error, hits) bind(c, name="coag_first_hit_kernel")
       import :: coag_first_hits, c_int64_t, c_double, c_int32_t
       type(coag_first_hits), intent(in) :: p
       integer(c_int64_t), value :: seed, first_id
       real(c_double), intent(out) :: mean, std_error
       integer(c_int64_t), intent(out) :: hits
       integer(c_int32_t) :: coag_first_hit_kernel
     end function
     function coag_thermal_default_config(out, size) bind(c, name="coag_thermal_default_config")
       import :: coag_thermal_config, c_size_t, c_int32_t
       type(coag_thermal_config), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_thermal_default_config
     end function
     ! counts(i) particles of size i at temperature temperatures(i), i = 1..len
     function coag_thermal_new(config, counts, temperatures, len, volume, out) bind(c, name="coag_thermal_new")
       import :: coag_thermal_config, c_int64_t, c_double, c_size_t, c_ptr, c_int32_t
       type(coag_thermal_config), intent(in) :: config
       integer(c_int64_t), intent(in) :: counts(*)
       real(c_double), intent(in) :: temperatures(*)
       integer(c_size_t), value :: len
       real(c_double), value :: volume
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_thermal_new
     end function
     subroutine coag_thermal_free(h) bind(c, name="coag_thermal_free")
       import :: c_ptr
       type(c_ptr), value :: h
     end subroutine
     function coag_thermal_advance_to(h, t, report) bind(c, name="coag_thermal_advance_to")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: h
       real(c_double), value :: t
       type(c_ptr), value :: report
       integer(c_int32_t) :: coag_thermal_advance_to
     end function
     ! time, particles, volume, max_size: c_loc of the variables, or c_null_ptr
     function coag_thermal_info(h, time, particles, volume, max_size) bind(c, name="coag_thermal_info")
       import :: c_ptr, c_int32_t
       type(c_ptr), value :: h, time, particles, volume, max_size
       integer(c_int32_t) :: coag_thermal_info
     end function
     ! moment (of order m), mean_temperature, energy: c_loc or c_null_ptr
     function coag_thermal_observe(h, m, moment, mean_temperature, energy) bind(c, name="coag_thermal_observe")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: h
       real(c_double), value :: m
       type(c_ptr), value :: moment, mean_temperature, energy
       integer(c_int32_t) :: coag_thermal_observe
     end function
     ! counts (int64), temperatures (double), len = max_size of coag_thermal_info: c_loc or c_null_ptr
     function coag_thermal_state(h, counts, temperatures, len) bind(c, name="coag_thermal_state")
       import :: c_ptr, c_size_t, c_int32_t
       type(c_ptr), value :: h, counts, temperatures
       integer(c_size_t), value :: len
       integer(c_int32_t) :: coag_thermal_state
     end function
     function coag_thermal_checkpoint_size(h, out) bind(c, name="coag_thermal_checkpoint_size")
       import :: c_ptr, c_size_t, c_int32_t
       type(c_ptr), value :: h
       integer(c_size_t), intent(out) :: out
       integer(c_int32_t) :: coag_thermal_checkpoint_size
     end function
     function coag_thermal_save(h, buf, n, written) bind(c, name="coag_thermal_save")
       import :: c_ptr, c_int8_t, c_size_t, c_int32_t
       type(c_ptr), value :: h
       integer(c_int8_t), intent(out) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_size_t), intent(out) :: written
       integer(c_int32_t) :: coag_thermal_save
     end function
     function coag_thermal_restore(h, buf, n) bind(c, name="coag_thermal_restore")
       import :: c_ptr, c_int8_t, c_size_t, c_int32_t
       type(c_ptr), value :: h
       integer(c_int8_t), intent(in) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_int32_t) :: coag_thermal_restore
     end function
     ! number, mean_temperature: c_loc or c_null_ptr
     function coag_thermal_model_exact(c, gamma, n0, t0, t, number, mean_temperature) &
          bind(c, name="coag_thermal_model_exact")
       import :: c_ptr, c_double, c_int32_t
       real(c_double), value :: c, gamma, n0, t0, t
       type(c_ptr), value :: number, mean_temperature
       integer(c_int32_t) :: coag_thermal_model_exact
     end function
     function coag_dsmc_default_config(out, size) bind(c, name="coag_dsmc_default_config")
       import :: coag_dsmc_config, c_size_t, c_int32_t
       type(coag_dsmc_config), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_dsmc_default_config
     end function
     ! sizes(p) and velocities(3p-2:3p), p = 1..n
     function coag_dsmc_new(config, sizes, velocities, n, volume, out) bind(c, name="coag_dsmc_new")
       import :: coag_dsmc_config, c_int64_t, c_double, c_size_t, c_ptr, c_int32_t
       type(coag_dsmc_config), intent(in) :: config
       integer(c_int64_t), intent(in) :: sizes(*)
       real(c_double), intent(in) :: velocities(*)
       integer(c_size_t), value :: n
       real(c_double), value :: volume
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_dsmc_new
     end function
     function coag_dsmc_new_maxwellian(config, counts, temperatures, len, volume, out) &
          bind(c, name="coag_dsmc_new_maxwellian")
       import :: coag_dsmc_config, c_int64_t, c_double, c_size_t, c_ptr, c_int32_t
       type(coag_dsmc_config), intent(in) :: config
       integer(c_int64_t), intent(in) :: counts(*)
       real(c_double), intent(in) :: temperatures(*)
       integer(c_size_t), value :: len
       real(c_double), value :: volume
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_dsmc_new_maxwellian
     end function
     subroutine coag_dsmc_free(h) bind(c, name="coag_dsmc_free")
       import :: c_ptr
       type(c_ptr), value :: h
     end subroutine
     function coag_dsmc_advance_to(h, t, report) bind(c, name="coag_dsmc_advance_to")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: h
       real(c_double), value :: t
       type(c_ptr), value :: report
       integer(c_int32_t) :: coag_dsmc_advance_to
     end function
     ! time, particles, volume: c_loc of the variables, or c_null_ptr
     function coag_dsmc_info(h, time, particles, volume) bind(c, name="coag_dsmc_info")
       import :: c_ptr, c_int32_t
       type(c_ptr), value :: h, time, particles, volume
       integer(c_int32_t) :: coag_dsmc_info
     end function
     ! momentum (3 doubles), energy, mean_temperature: c_loc or c_null_ptr
     function coag_dsmc_observe(h, momentum, energy, mean_temperature) bind(c, name="coag_dsmc_observe")
       import :: c_ptr, c_int32_t
       type(c_ptr), value :: h, momentum, energy, mean_temperature
       integer(c_int32_t) :: coag_dsmc_observe
     end function
     ! sizes (n int64), velocities (3n doubles): c_loc or c_null_ptr
     function coag_dsmc_particles(h, sizes, velocities, n) bind(c, name="coag_dsmc_particles")
       import :: c_ptr, c_size_t, c_int32_t
       type(c_ptr), value :: h, sizes, velocities
       integer(c_size_t), value :: n
       integer(c_int32_t) :: coag_dsmc_particles
     end function
     function coag_dsmc_checkpoint_size(h, out) bind(c, name="coag_dsmc_checkpoint_size")
       import :: c_ptr, c_size_t, c_int32_t
       type(c_ptr), value :: h
       integer(c_size_t), intent(out) :: out
       integer(c_int32_t) :: coag_dsmc_checkpoint_size
     end function
     function coag_dsmc_save(h, buf, n, written) bind(c, name="coag_dsmc_save")
       import :: c_ptr, c_int8_t, c_size_t, c_int32_t
       type(c_ptr), value :: h
       integer(c_int8_t), intent(out) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_size_t), intent(out) :: written
       integer(c_int32_t) :: coag_dsmc_save
     end function
     function coag_dsmc_restore(h, buf, n) bind(c, name="coag_dsmc_restore")
       import :: c_ptr, c_int8_t, c_size_t, c_int32_t
       type(c_ptr), value :: h
       integer(c_int8_t), intent(in) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_int32_t) :: coag_dsmc_restore
     end function
     function coag_kernel_new_constant(k0, out) bind(c, name="coag_kernel_new_constant")
       import :: c_double, c_ptr, c_int32_t
       real(c_double), value :: k0
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_kernel_new_constant
     end function
     function coag_kernel_new_additive(min_size, out) bind(c, name="coag_kernel_new_additive")
       import :: c_double, c_ptr, c_int32_t
       real(c_double), value :: min_size
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_kernel_new_additive
     end function
     function coag_kernel_new_multiplicative(out) bind(c, name="coag_kernel_new_multiplicative")
       import :: c_ptr, c_int32_t
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_kernel_new_multiplicative
     end function
     function coag_kernel_new_brownian(out) bind(c, name="coag_kernel_new_brownian")
       import :: c_ptr, c_int32_t
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_kernel_new_brownian
     end function
     function coag_kernel_new_free_molecular(min_size, out) bind(c, name="coag_kernel_new_free_molecular")
       import :: c_double, c_ptr, c_int32_t
       real(c_double), value :: min_size
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_kernel_new_free_molecular
     end function
     subroutine coag_kernel_free(k) bind(c, name="coag_kernel_free")
       import :: c_ptr
       type(c_ptr), value :: k
     end subroutine
     function coag_fragmentation_new_binary_uniform(lambda, out) &
          bind(c, name="coag_fragmentation_new_binary_uniform")
       import :: c_double, c_ptr, c_int32_t
       real(c_double), value :: lambda
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_fragmentation_new_binary_uniform
     end function
     subroutine coag_fragmentation_free(f) bind(c, name="coag_fragmentation_free")
       import :: c_ptr
       type(c_ptr), value :: f
     end subroutine
     ! size: c_sizeof(out)
     function coag_massflow_default_config(out, size) bind(c, name="coag_massflow_default_config")
       import :: coag_massflow_config, c_int32_t, c_size_t
       type(coag_massflow_config), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_massflow_default_config
     end function
     ! size: c_sizeof(out)
     function coag_counts_default_config(out, size) bind(c, name="coag_counts_default_config")
       import :: coag_counts_config, c_int32_t, c_size_t
       type(coag_counts_config), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_counts_default_config
     end function
     ! size: c_sizeof(out)
     function coag_eventflow_default_config(out, size) bind(c, name="coag_eventflow_default_config")
       import :: coag_eventflow_config, c_int32_t, c_size_t
       type(coag_eventflow_config), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_eventflow_default_config
     end function
     function coag_eventflow_new(config, kernel, frag, sizes, n, out) bind(c, name="coag_eventflow_new")
       import :: coag_eventflow_config, c_ptr, c_double, c_size_t, c_int32_t
       type(coag_eventflow_config), intent(in) :: config
       type(c_ptr), value :: kernel, frag
       real(c_double), intent(in) :: sizes(*)
       integer(c_size_t), value :: n
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_eventflow_new
     end function
     function coag_massflow_new(config, kernel, frag, sizes, n, out) bind(c, name="coag_massflow_new")
       import :: coag_massflow_config, c_ptr, c_double, c_size_t, c_int32_t
       type(coag_massflow_config), intent(in) :: config
       type(c_ptr), value :: kernel, frag
       real(c_double), intent(in) :: sizes(*)
       integer(c_size_t), value :: n
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_massflow_new
     end function
     function coag_massflow_workspace_size(n, out) bind(c, name="coag_massflow_workspace_size")
       import :: c_size_t, c_int32_t
       integer(c_size_t), value :: n
       integer(c_size_t), intent(out) :: out
       integer(c_int32_t) :: coag_massflow_workspace_size
     end function
     ! the workspace (real(c_double) array, c_loc of it) must stay allocated until
     ! coag_sim_free
     function coag_massflow_new_in(config, kernel, frag, sizes, n, workspace, workspace_bytes, out) &
          bind(c, name="coag_massflow_new_in")
       import :: coag_massflow_config, c_ptr, c_double, c_size_t, c_int32_t
       type(coag_massflow_config), intent(in) :: config
       type(c_ptr), value :: kernel, frag
       real(c_double), intent(in) :: sizes(*)
       integer(c_size_t), value :: n
       type(c_ptr), value :: workspace
       integer(c_size_t), value :: workspace_bytes
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_massflow_new_in
     end function
     function coag_eventflow_workspace_size(config, frag, n, out) &
          bind(c, name="coag_eventflow_workspace_size")
       import :: coag_eventflow_config, c_ptr, c_size_t, c_int32_t
       type(coag_eventflow_config), intent(in) :: config
       type(c_ptr), value :: frag
       integer(c_size_t), value :: n
       integer(c_size_t), intent(out) :: out
       integer(c_int32_t) :: coag_eventflow_workspace_size
     end function
     ! the workspace (real(c_double) array, c_loc of it) must stay allocated until
     ! coag_sim_free
     function coag_eventflow_new_in(config, kernel, frag, sizes, n, workspace, workspace_bytes, out) &
          bind(c, name="coag_eventflow_new_in")
       import :: coag_eventflow_config, c_ptr, c_double, c_size_t, c_int32_t
       type(coag_eventflow_config), intent(in) :: config
       type(c_ptr), value :: kernel, frag
       real(c_double), intent(in) :: sizes(*)
       integer(c_size_t), value :: n
       type(c_ptr), value :: workspace
       integer(c_size_t), value :: workspace_bytes
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_eventflow_new_in
     end function
     function coag_sim_bucket_mode(sim, out) bind(c, name="coag_sim_bucket_mode")
       import :: c_ptr, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int32_t), intent(out) :: out
       integer(c_int32_t) :: coag_sim_bucket_mode
     end function
     function coag_sim_method(sim, out) bind(c, name="coag_sim_method")
       import :: c_ptr, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int32_t), intent(out) :: out
       integer(c_int32_t) :: coag_sim_method
     end function
     function coag_counts_new(config, kernel, counts, n, out) bind(c, name="coag_counts_new")
       import :: coag_counts_config, c_ptr, c_int64_t, c_size_t, c_int32_t
       type(coag_counts_config), intent(in) :: config
       type(c_ptr), value :: kernel
       integer(c_int64_t), intent(in) :: counts(*)
       integer(c_size_t), value :: n
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_counts_new
     end function
     ! size: c_sizeof(out)
     function coag_step_report_init(out, size) bind(c, name="coag_step_report_init")
       import :: coag_step_report, c_int32_t, c_size_t
       type(coag_step_report), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_step_report_init
     end function
     subroutine coag_sim_free(sim) bind(c, name="coag_sim_free")
       import :: c_ptr
       type(c_ptr), value :: sim
     end subroutine
     function coag_sim_advance_to(sim, t, report) bind(c, name="coag_sim_advance_to")
       import :: c_ptr, c_double, coag_step_report, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), value :: t
       type(coag_step_report), intent(inout) :: report
       integer(c_int32_t) :: coag_sim_advance_to
     end function
     function coag_sim_time(sim, out) bind(c, name="coag_sim_time")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), intent(out) :: out
       integer(c_int32_t) :: coag_sim_time
     end function
     function coag_sim_moment(sim, m, out) bind(c, name="coag_sim_moment")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), value :: m
       real(c_double), intent(out) :: out
       integer(c_int32_t) :: coag_sim_moment
     end function
     function coag_sim_particle_count(sim, out) bind(c, name="coag_sim_particle_count")
       import :: c_ptr, c_int64_t, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(out) :: out
       integer(c_int32_t) :: coag_sim_particle_count
     end function
     function coag_sim_state_len(sim, out) bind(c, name="coag_sim_state_len")
       import :: c_ptr, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       integer(c_size_t), intent(out) :: out
       integer(c_int32_t) :: coag_sim_state_len
     end function
     function coag_sim_get_sizes(sim, buf, n) bind(c, name="coag_sim_get_sizes")
       import :: c_ptr, c_double, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), intent(out) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_int32_t) :: coag_sim_get_sizes
     end function
     function coag_sim_set_sizes(sim, buf, n) bind(c, name="coag_sim_set_sizes")
       import :: c_ptr, c_double, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), intent(in) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_int32_t) :: coag_sim_set_sizes
     end function
     function coag_sim_get_counts(sim, buf, n, volume) bind(c, name="coag_sim_get_counts")
       import :: c_ptr, c_int64_t, c_size_t, c_double, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(out) :: buf(*)
       integer(c_size_t), value :: n
       real(c_double), intent(out) :: volume
       integer(c_int32_t) :: coag_sim_get_counts
     end function
     function coag_sim_set_kernel(sim, kernel) bind(c, name="coag_sim_set_kernel")
       import :: c_ptr, c_int32_t
       type(c_ptr), value :: sim, kernel
       integer(c_int32_t) :: coag_sim_set_kernel
     end function
     function coag_exact_moment(solution, m, t, out) bind(c, name="coag_exact_moment")
       import :: c_int32_t, c_double
       integer(c_int32_t), value :: solution, m
       real(c_double), value :: t
       real(c_double), intent(out) :: out
       integer(c_int32_t) :: coag_exact_moment
     end function
     function coag_last_error_message(buf, n, out_len) bind(c, name="coag_last_error_message")
       import :: c_char, c_size_t, c_int32_t
       character(kind=c_char), intent(out) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_size_t), intent(out) :: out_len
       integer(c_int32_t) :: coag_last_error_message
     end function
     function coag_version() bind(c, name="coag_version")
       import :: c_ptr
       type(c_ptr) :: coag_version
     end function
     function coag_status_name(status) bind(c, name="coag_status_name")
       import :: c_ptr, c_int32_t
       integer(c_int32_t), value :: status
       type(c_ptr) :: coag_status_name
     end function
     function coag_exact_density(solution, k, t, out) bind(c, name="coag_exact_density")
       import :: c_int32_t, c_int64_t, c_double
       integer(c_int32_t), value :: solution
       integer(c_int64_t), value :: k
       real(c_double), value :: t
       real(c_double), intent(out) :: out
       integer(c_int32_t) :: coag_exact_density
     end function
     function coag_kernel_new_product(a, out) bind(c, name="coag_kernel_new_product")
       import :: c_double, c_ptr, c_int32_t
       real(c_double), value :: a
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_kernel_new_product
     end function
     function coag_kernel_new_homogeneous(gamma, out) bind(c, name="coag_kernel_new_homogeneous")
       import :: c_double, c_ptr, c_int32_t
       real(c_double), value :: gamma
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_kernel_new_homogeneous
     end function
     function coag_kernel_new_user(desc, out) bind(c, name="coag_kernel_new_user")
       import :: coag_user_kernel, c_ptr, c_int32_t
       type(coag_user_kernel), intent(in) :: desc
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_kernel_new_user
     end function
     function coag_kernel_rate(kernel, x, y, out) bind(c, name="coag_kernel_rate")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: kernel
       real(c_double), value :: x, y
       real(c_double), intent(out) :: out
       integer(c_int32_t) :: coag_kernel_rate
     end function
     function coag_fragmentation_new_user(desc, out) bind(c, name="coag_fragmentation_new_user")
       import :: coag_user_fragmentation, c_ptr, c_int32_t
       type(coag_user_fragmentation), intent(in) :: desc
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_fragmentation_new_user
     end function
     function coag_sim_set_work_limit(sim, units) bind(c, name="coag_sim_set_work_limit")
       import :: c_ptr, c_int64_t, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int64_t), value :: units
       integer(c_int32_t) :: coag_sim_set_work_limit
     end function
     ! cancel: c_funloc of an integer(c_int32_t) function(user_data) bind(c), or
     ! c_null_funptr
     function coag_sim_set_cancel_callback(sim, cancel, user_data) bind(c, name="coag_sim_set_cancel_callback")
       import :: c_ptr, c_funptr, c_int32_t
       type(c_ptr), value :: sim
       type(c_funptr), value :: cancel
       type(c_ptr), value :: user_data
       integer(c_int32_t) :: coag_sim_set_cancel_callback
     end function
     function coag_sim_totals(sim, out) bind(c, name="coag_sim_totals")
       import :: c_ptr, coag_step_report, c_int32_t
       type(c_ptr), value :: sim
       type(coag_step_report), intent(inout) :: out
       integer(c_int32_t) :: coag_sim_totals
     end function
     function coag_sim_concentration(sim, a, b, out) bind(c, name="coag_sim_concentration")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), value :: a, b
       real(c_double), intent(out) :: out
       integer(c_int32_t) :: coag_sim_concentration
     end function
     function coag_sim_gel_mass(sim, out) bind(c, name="coag_sim_gel_mass")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), intent(out) :: out
       integer(c_int32_t) :: coag_sim_gel_mass
     end function
     function coag_sim_occupied(sim, out) bind(c, name="coag_sim_occupied")
       import :: c_ptr, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       integer(c_size_t), intent(out) :: out
       integer(c_int32_t) :: coag_sim_occupied
     end function
     function coag_sim_get_pairs(sim, sizes, counts, n, volume, written) bind(c, name="coag_sim_get_pairs")
       import :: c_ptr, c_int64_t, c_size_t, c_double, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(out) :: sizes(*), counts(*)
       integer(c_size_t), value :: n
       real(c_double), intent(out) :: volume
       integer(c_size_t), intent(out) :: written
       integer(c_int32_t) :: coag_sim_get_pairs
     end function
     function coag_sim_set_pairs(sim, sizes, counts, n, volume) bind(c, name="coag_sim_set_pairs")
       import :: c_ptr, c_int64_t, c_size_t, c_double, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(in) :: sizes(*), counts(*)
       integer(c_size_t), value :: n
       real(c_double), value :: volume
       integer(c_int32_t) :: coag_sim_set_pairs
     end function
     function coag_sim_set_counts(sim, counts, n, volume) bind(c, name="coag_sim_set_counts")
       import :: c_ptr, c_int64_t, c_size_t, c_double, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int64_t), intent(in) :: counts(*)
       integer(c_size_t), value :: n
       real(c_double), value :: volume
       integer(c_int32_t) :: coag_sim_set_counts
     end function
     function coag_sim_set_fragmentation(sim, frag) bind(c, name="coag_sim_set_fragmentation")
       import :: c_ptr, c_int32_t
       type(c_ptr), value :: sim, frag
       integer(c_int32_t) :: coag_sim_set_fragmentation
     end function
     function coag_sim_set_dt(sim, dt) bind(c, name="coag_sim_set_dt")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), value :: dt
       integer(c_int32_t) :: coag_sim_set_dt
     end function
     function coag_sim_set_time(sim, t) bind(c, name="coag_sim_set_time")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), value :: t
       integer(c_int32_t) :: coag_sim_set_time
     end function
     function coag_sim_set_mass(sim, mass) bind(c, name="coag_sim_set_mass")
       import :: c_ptr, c_double, c_int32_t
       type(c_ptr), value :: sim
       real(c_double), value :: mass
       integer(c_int32_t) :: coag_sim_set_mass
     end function
     ! size: c_sizeof(out)
     function coag_sim_massflow_config(sim, out, size) bind(c, name="coag_sim_massflow_config")
       import :: c_ptr, coag_massflow_config, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       type(coag_massflow_config), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_sim_massflow_config
     end function
     ! size: c_sizeof(out)
     function coag_sim_eventflow_config(sim, out, size) bind(c, name="coag_sim_eventflow_config")
       import :: c_ptr, coag_eventflow_config, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       type(coag_eventflow_config), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_sim_eventflow_config
     end function
     ! size: c_sizeof(out)
     function coag_sim_counts_config(sim, out, size) bind(c, name="coag_sim_counts_config")
       import :: c_ptr, coag_counts_config, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       type(coag_counts_config), intent(out) :: out
       integer(c_size_t), value :: size
       integer(c_int32_t) :: coag_sim_counts_config
     end function
     ! next: c_funloc of an integer(c_int64_t) function(user_data) bind(c), or
     ! c_null_funptr
     function coag_sim_set_rng_callback(sim, next, user_data) bind(c, name="coag_sim_set_rng_callback")
       import :: c_ptr, c_funptr, c_int32_t
       type(c_ptr), value :: sim
       type(c_funptr), value :: next
       type(c_ptr), value :: user_data
       integer(c_int32_t) :: coag_sim_set_rng_callback
     end function
     function coag_sim_reseed(sim, seed, stream) bind(c, name="coag_sim_reseed")
       import :: c_ptr, c_int64_t, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int64_t), value :: seed, stream
       integer(c_int32_t) :: coag_sim_reseed
     end function
     function coag_sim_checkpoint_size(sim, out) bind(c, name="coag_sim_checkpoint_size")
       import :: c_ptr, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       integer(c_size_t), intent(out) :: out
       integer(c_int32_t) :: coag_sim_checkpoint_size
     end function
     function coag_sim_checkpoint(sim, buf, n, written) bind(c, name="coag_sim_checkpoint")
       import :: c_ptr, c_int8_t, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int8_t), intent(out) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_size_t), intent(out) :: written
       integer(c_int32_t) :: coag_sim_checkpoint
     end function
     function coag_sim_restore(sim, buf, n) bind(c, name="coag_sim_restore")
       import :: c_ptr, c_int8_t, c_size_t, c_int32_t
       type(c_ptr), value :: sim
       integer(c_int8_t), intent(in) :: buf(*)
       integer(c_size_t), value :: n
       integer(c_int32_t) :: coag_sim_restore
     end function
     function coag_sim_clone(sim, out) bind(c, name="coag_sim_clone")
       import :: c_ptr, c_int32_t
       type(c_ptr), value :: sim
       type(c_ptr), intent(out) :: out
       integer(c_int32_t) :: coag_sim_clone
     end function
  end interface

contains

  !> The last error message on this thread, as a Fortran string.
  function coag_error_message() result(msg)
    character(len=:), allocatable :: msg
    character(kind=c_char) :: buf(512)
    integer(c_size_t) :: n
    integer(c_int32_t) :: st
    integer :: i, k
    st = coag_last_error_message(buf, int(size(buf), c_size_t), n)
    k = c_strlen_like(buf)
    allocate(character(len=k) :: msg)
    do i = 1, k
       msg(i:i) = buf(i)
    end do
  end function coag_error_message

  pure integer function c_strlen_like(buf)
    character(kind=c_char), intent(in) :: buf(:)
    integer :: i
    c_strlen_like = size(buf)
    do i = 1, size(buf)
       if (buf(i) == c_null_char) then
          c_strlen_like = i - 1
          return
       end if
    end do
  end function c_strlen_like

end module coagula
