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
  use coagula_types   ! the constants, derived types and callback interfaces (include/coagula_types.f90)
  implicit none

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
     integer(c_int32_t) function coag_kernel_set_user_blocks(kernel, sup_block, low_rank_loose) &
         bind(c, name="coag_kernel_set_user_blocks")
       import
       type(c_ptr), value :: kernel
       type(c_funptr), value :: sup_block
       integer(c_int32_t), value :: low_rank_loose
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
     integer(c_int32_t) function coag_sim_set_source_sizes(sim, rate, sizes, len) bind(c, name="coag_sim_set_source_sizes")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: rate
       real(c_double), intent(in) :: sizes(*)
       integer(c_size_t), value :: len
     end function
     integer(c_int32_t) function coag_sim_set_source_schedule(sim, times, rates, len) &
          bind(c, name="coag_sim_set_source_schedule")
       import
       type(c_ptr), value :: sim
       real(c_double), intent(in) :: times(*), rates(*)
       integer(c_size_t), value :: len
     end function
     integer(c_int32_t) function coag_sim_set_source_callback(sim, rate, user_data, bound, tag) &
          bind(c, name="coag_sim_set_source_callback")
       import
       type(c_ptr), value :: sim, user_data
       type(c_funptr), value :: rate               ! coag_rate_callback or NULL
       real(c_double), value :: bound
       integer(c_int64_t), value :: tag
     end function
     integer(c_int32_t) function coag_sim_set_removal_callback(sim, rate, user_data, bound, tag) &
          bind(c, name="coag_sim_set_removal_callback")
       import
       type(c_ptr), value :: sim, user_data
       type(c_funptr), value :: rate               ! coag_rate_callback or NULL
       real(c_double), value :: bound
       integer(c_int64_t), value :: tag
     end function
     integer(c_int32_t) function coag_sim_set_growth_callback(sim, rate, user_data, bound, tag) &
          bind(c, name="coag_sim_set_growth_callback")
       import
       type(c_ptr), value :: sim, user_data
       type(c_funptr), value :: rate               ! coag_rate_callback or NULL
       real(c_double), value :: bound
       integer(c_int64_t), value :: tag
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
     integer(c_int32_t) function coag_sim_set_growth_step(sim, step) bind(c, name="coag_sim_set_growth_step")
       import
       type(c_ptr), value :: sim
       real(c_double), value :: step
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
     integer(c_int32_t) function coag_sim_project(sim, pivots, len, numbers, outside) bind(c, name="coag_sim_project")
       import
       type(c_ptr), value :: sim
       real(c_double), intent(in) :: pivots(*)
       integer(c_size_t), value :: len
       real(c_double), intent(out) :: numbers(*)
       real(c_double), intent(out) :: outside(4)  ! N_below, M_below, N_above, M_above
     end function
     integer(c_int32_t) function coag_sim_set_classes(sim, pivots, numbers, len) bind(c, name="coag_sim_set_classes")
       import
       type(c_ptr), value :: sim
       real(c_double), intent(in) :: pivots(*), numbers(*)
       integer(c_size_t), value :: len
     end function
     integer(c_int32_t) function coag_class_rates(before, after, len, dt, out) bind(c, name="coag_class_rates")
       import
       real(c_double), intent(in) :: before(*), after(*)
       integer(c_size_t), value :: len
       real(c_double), value :: dt
       real(c_double), intent(out) :: out(*)
     end function
     ! ------------------------------------------------------------ the sectional reference
     integer(c_int32_t) function coag_sectional_new(kernel, pivots, len, out) bind(c, name="coag_sectional_new")
       import
       type(c_ptr), value :: kernel
       real(c_double), intent(in) :: pivots(*)
       integer(c_size_t), value :: len
       type(c_ptr), intent(out) :: out
     end function
     subroutine coag_sectional_free(s) bind(c, name="coag_sectional_free")
       import
       type(c_ptr), value :: s
     end subroutine
     integer(c_int32_t) function coag_sectional_set_processes(s, source_rate, source_size, removal_coefficient, &
          removal_exponent, growth_coefficient, growth_exponent) bind(c, name="coag_sectional_set_processes")
       import
       type(c_ptr), value :: s
       real(c_double), value :: source_rate, source_size, removal_coefficient, removal_exponent
       real(c_double), value :: growth_coefficient, growth_exponent
     end function
     integer(c_int32_t) function coag_sectional_set_numbers(s, numbers, len) bind(c, name="coag_sectional_set_numbers")
       import
       type(c_ptr), value :: s
       real(c_double), intent(in) :: numbers(*)
       integer(c_size_t), value :: len
     end function
     integer(c_int32_t) function coag_sectional_add(s, size, number) bind(c, name="coag_sectional_add")
       import
       type(c_ptr), value :: s
       real(c_double), value :: size, number
     end function
     integer(c_int32_t) function coag_sectional_advance_to(s, t, dt) bind(c, name="coag_sectional_advance_to")
       import
       type(c_ptr), value :: s
       real(c_double), value :: t, dt
     end function
     integer(c_int32_t) function coag_sectional_numbers(s, out, len) bind(c, name="coag_sectional_numbers")
       import
       type(c_ptr), value :: s
       real(c_double), intent(out) :: out(*)
       integer(c_size_t), value :: len
     end function
     integer(c_int32_t) function coag_sectional_moment(s, order, moment, time) bind(c, name="coag_sectional_moment")
       import
       type(c_ptr), value :: s
       real(c_double), value :: order
       real(c_double), intent(out) :: moment, time
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
