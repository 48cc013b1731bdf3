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
       COAG_BAD_CHECKPOINT = 8, COAG_PANIC = 9
  integer(c_int32_t), parameter :: COAG_POINTS_NIEDERREITER = 0, COAG_POINTS_SOBOL = 1, &
       COAG_POINTS_MONTE_CARLO = 2
  integer(c_int32_t), parameter :: COAG_RANDOMIZATION_NONE = 0, COAG_RANDOMIZATION_SHIFT = 1, &
       COAG_RANDOMIZATION_MATOUSEK = 2, COAG_RANDOMIZATION_OWEN = 3
  integer(c_int32_t), parameter :: COAG_METHOD_LOWRANK = 0, COAG_METHOD_INVERSE = 1, &
       COAG_METHOD_REJECTION = 2, COAG_METHOD_LOWRANK_TREE = 3
  integer(c_int32_t), parameter :: COAG_EXACT_CONSTANT = 0, COAG_EXACT_ADDITIVE = 1, &
       COAG_EXACT_MULTIPLICATIVE = 2, COAG_EXACT_MARCUS_LUSHNIKOV = 3, COAG_EXACT_COAG_FRAG = 4

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
  end type coag_counts_config

  ! set struct_size = c_sizeof(report) before passing a report (or call
  ! coag_step_report_init)
  type, bind(c) :: coag_step_report
     integer(c_size_t) :: struct_size
     real(c_double) :: time
     integer(c_int64_t) :: events, proposals, rejections, bound_violations, clipped, doublings
     integer(c_int64_t) :: removed, bounces
  end type coag_step_report

  interface
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
