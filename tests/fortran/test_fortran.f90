! Fortran client of libcoagula through the ISO_C_BINDING module include/coagula.f90:
! the constant-kernel exact solution from 32 low-rank replicas (6.07 standard errors: Student t_31 at 1e-6), and
! Lécot's coagulation-fragmentation test with the mass-flow scheme.
program test_fortran
  use, intrinsic :: iso_c_binding
  use coagula
  implicit none
  type(c_ptr) :: k, f, sim, sim2
  real(c_double), allocatable, target :: ws(:)
  integer(c_size_t) :: wbytes
  integer(c_int32_t) :: method
  real(c_double) :: m2b
  type(coag_counts_config) :: lc
  type(coag_massflow_config) :: mc
  type(coag_step_report) :: rep
  integer(c_int64_t) :: counts(1)
  real(c_double) :: m0, s1, s2, mean, se, exact, m2
  real(c_double), allocatable :: sizes(:)
  integer :: r, h, nfail, nchecks
  integer, parameter :: reps = 32

  nfail = 0
  nchecks = 0
  call ok(coag_kernel_new_constant(1.0_c_double, k))
  call ok(coag_step_report_init(rep, c_sizeof(rep)))
  s1 = 0
  s2 = 0
  do r = 1, reps
     call ok(coag_counts_default_config(lc, c_sizeof(lc)))
     lc%seed = int(100 + r, c_int64_t)
     counts(1) = 8192
     call ok(coag_counts_new(lc, k, counts, 1_c_size_t, sim))
     if (r == 1) then
        call ok(coag_sim_method(sim, method))
        call check(method == COAG_METHOD_LOWRANK, "the default method is bucketed low-rank")
     end if
     do h = 1, 10
        call ok(coag_sim_advance_to(sim, 0.2_c_double * h, rep))
     end do
     call ok(coag_sim_moment(sim, 0.0_c_double, m0))
     s1 = s1 + m0
     s2 = s2 + m0 * m0
     call coag_sim_free(sim)
  end do
  mean = s1 / reps
  se = sqrt((s2 / reps - mean * mean) / (reps - 1))
  call ok(coag_exact_moment(COAG_EXACT_CONSTANT, 0_c_int32_t, 2.0_c_double, exact))
  call check(abs(mean - exact) < 6.072_c_double * se, "low-rank M0(2) within 6.07 SE of the exact value")

  call ok(coag_fragmentation_new_binary_uniform(1.0_c_double, f))
  call ok(coag_massflow_default_config(mc, c_sizeof(mc)))
  allocate(sizes(4096))
  sizes = 1.0_c_double
  call ok(coag_massflow_new(mc, k, f, sizes, size(sizes, kind=c_size_t), sim))
  call ok(coag_sim_advance_to(sim, 1.0_c_double, rep))
  call ok(coag_sim_moment(sim, 2.0_c_double, m2))
  call ok(coag_exact_moment(COAG_EXACT_COAG_FRAG, 2_c_int32_t, 1.0_c_double, exact))
  call check(abs(m2 - exact) < 5e-3_c_double, "mass-flow M2(1) close to the exact value")
  call check(rep%proposals == 100 * 4096, "one proposal per particle and step")
  call ok(coag_sim_get_sizes(sim, sizes, size(sizes, kind=c_size_t)))
  call check(all(sizes(2:) >= sizes(:size(sizes) - 1)), "sizes come back sorted")
  ! the same sim in a workspace the caller owns runs bit for bit alike
  call ok(coag_massflow_workspace_size(size(sizes, kind=c_size_t), wbytes))
  call check(wbytes == 6 * 8 * size(sizes), "workspace of 6 N doubles")
  allocate(ws(wbytes / 8))
  sizes = 1.0_c_double
  call ok(coag_massflow_new_in(mc, k, f, sizes, size(sizes, kind=c_size_t), c_loc(ws), wbytes, sim2))
  call ok(coag_sim_advance_to(sim2, 1.0_c_double, rep))
  call ok(coag_sim_moment(sim2, 2.0_c_double, m2b))
  call check(transfer(m2b, 0_c_int64_t) == transfer(m2, 0_c_int64_t), "caller workspace: the same M2 bit for bit")
  call coag_sim_free(sim2)
  deallocate(ws)
  ! errors: a step back in time fails and names the problem
  call check(coag_sim_advance_to(sim, 0.5_c_double, rep) == COAG_TIME_BACKWARDS, "time backwards refused")
  call check(index(coag_error_message(), "before the current time") > 0, "error message")
  call coag_sim_free(sim)
  call coag_fragmentation_free(f)
  call coag_kernel_free(k)
  print '(a, i0, a, i0, a)', "test_fortran: ", nchecks - nfail, " passed, ", nfail, " failed"
  if (nfail /= 0) stop 1

contains

  subroutine ok(status)
    integer(c_int32_t), intent(in) :: status
    nchecks = nchecks + 1
    if (status /= COAG_OK) then
       print *, "call failed: ", coag_error_message()
       stop 1
    end if
  end subroutine ok

  subroutine check(cond, what)
    logical, intent(in) :: cond
    character(len=*), intent(in) :: what
    nchecks = nchecks + 1
    if (.not. cond) then
       nfail = nfail + 1
       print *, "check failed: ", what
    end if
  end subroutine check

end program test_fortran
