! Fortran client of libcoagula through the ISO_C_BINDING module include/coagula.f90:
! the constant-kernel exact solution from 32 low-rank replicas (6.07 standard errors: Student t_31 at 1e-6), and
! Lécot's coagulation-fragmentation test with the mass-flow scheme.
! callbacks for the user kernels and the host hooks (bind(c) module procedures)
module test_callbacks
  use, intrinsic :: iso_c_binding
  implicit none
  integer(c_int64_t) :: rng_state = 88172645463325252_c_int64_t
contains
  function one_rate(x, y, ud) bind(c) result(r)
    real(c_double), value :: x, y
    type(c_ptr), value :: ud
    real(c_double) :: r
    r = 1.0_c_double + 0.0_c_double * (x + y)
    if (c_associated(ud)) r = 2.0_c_double
  end function
  function one_sup(lo, hi, ud) bind(c) result(r)
    real(c_double), value :: lo, hi
    type(c_ptr), value :: ud
    real(c_double) :: r
    r = 1.0_c_double + 0.0_c_double * (lo + hi)
    if (c_associated(ud)) r = 2.0_c_double
  end function
  function frag_rate(x, ud) bind(c) result(r)
    real(c_double), value :: x
    type(c_ptr), value :: ud
    real(c_double) :: r
    r = 1.0_c_double + 0.0_c_double * x
    if (c_associated(ud)) r = 2.0_c_double
  end function
  function frag_piece(x, u, ud) bind(c) result(r)
    real(c_double), value :: x, u
    type(c_ptr), value :: ud
    real(c_double) :: r
    r = x * sqrt(u)
    if (c_associated(ud)) r = x
  end function
  function cancel_now(ud) bind(c) result(r)
    type(c_ptr), value :: ud
    integer(c_int32_t) :: r
    r = 1
    if (c_associated(ud)) r = 0
  end function
  function rng_next(ud) bind(c) result(r)
    type(c_ptr), value :: ud
    integer(c_int64_t) :: r
    rng_state = ieor(rng_state, ishft(rng_state, 13))
    rng_state = ieor(rng_state, ishft(rng_state, -7))
    rng_state = ieor(rng_state, ishft(rng_state, 17))
    r = rng_state
    if (c_associated(ud)) r = 0
  end function
  ! Langevin callbacks: |u|^2 as an observable, friction b = -u as a drift
  function u_squared(x, u, dim, ud) bind(c) result(r)
    real(c_double), intent(in) :: x(*), u(*)
    integer(c_size_t), value :: dim
    type(c_ptr), value :: ud
    real(c_double) :: r
    r = sum(u(1:dim)**2) + 0.0_c_double * x(1)
    if (c_associated(ud)) r = 0
  end function
  function friction_drift(t, x, u, dim, out, ud) bind(c) result(r)
    real(c_double), value :: t
    real(c_double), intent(in) :: x(*), u(*)
    integer(c_size_t), value :: dim
    real(c_double), intent(out) :: out(*)
    type(c_ptr), value :: ud
    integer(c_int32_t) :: r
    out(1:dim) = -u(1:dim) + 0.0_c_double * (t + x(1))
    r = 0
    if (c_associated(ud)) r = 1
  end function
end module test_callbacks

program test_fortran
  use, intrinsic :: iso_c_binding
  use coagula
  use test_callbacks
  implicit none
  type(c_ptr) :: k2, ku, fu, sa, sb, sm
  type(coag_user_kernel) :: uk
  type(coag_user_fragmentation) :: uf
  type(coag_massflow_config) :: mc2
  integer(c_int64_t) :: c2(2), np
  integer(c_int64_t), allocatable :: ps(:), pc(:)
  integer(c_int8_t), allocatable :: ck(:)
  integer(c_size_t) :: nocc, nw, nck
  real(c_double) :: d, vol
  integer(c_int32_t) :: st
  character(kind=c_char) :: msgbuf(256)
  type(c_ptr) :: k, f, sim, sim2
  real(c_double), allocatable, target :: ws(:)
  integer(c_size_t) :: wbytes
  integer(c_int32_t) :: method
  real(c_double) :: m2b
  type(coag_counts_config) :: lc
  type(coag_massflow_config) :: mc
  type(coag_eventflow_config) :: ec, ec2
  real(c_double) :: ones(2048)
  real(c_double), allocatable :: xa(:), xb(:)
  type(coag_step_report) :: rep
  integer(c_int64_t) :: counts(1)
  real(c_double) :: m0, s1, s2, mean, se, exact, m2
  real(c_double), allocatable :: sizes(:)
  integer :: r, h, nfail, nchecks
  integer, parameter :: reps = 32
  ! temperature-dependent MC
  type(coag_thermal_config) :: thc
  type(c_ptr) :: th
  real(c_double), target :: tm, tn_exact, tt_exact, tmean, ttime, tvol
  integer(c_int64_t), target :: tparts
  integer(c_size_t), target :: tmax
  integer(c_int64_t), allocatable, target :: tcounts(:)
  real(c_double), allocatable, target :: ttemps(:)
  integer(c_int8_t), allocatable :: tck(:)
  integer(c_size_t) :: tnck, tnw
  ! DSMC
  type(coag_dsmc_config) :: dsc
  type(c_ptr) :: ds
  real(c_double), target :: dp0(3), dp1(3), de0, de1, dtime
  integer(c_int64_t), target :: dn
  integer(c_int64_t), allocatable, target :: dsizes(:)
  real(c_double), allocatable, target :: dvel(:)
  ! Langevin
  type(coag_langevin_config) :: lgc
  type(coag_first_hits) :: fh
  type(c_ptr) :: lb
  real(c_double), target :: lt
  integer(c_size_t), target :: ldim
  integer(c_int64_t), target :: ln
  integer(c_int64_t) :: lhitc
  real(c_double), allocatable, target :: lxs(:), lfirst(:), lws(:)
  integer(c_int64_t), allocatable, target :: lhits(:)
  integer(c_int8_t), allocatable :: lck(:)
  integer(c_size_t) :: lnck, lnw, lwb

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
        call ok(coag_sim_bucket_mode(sim, method))
        call check(method == COAG_BUCKET_COUNTED, "8192 particles run on the counted engine")
     end if
     do h = 1, 10
        call ok(coag_sim_advance_to(sim, 0.2_c_double * h, rep))
     end do
     call ok(coag_sim_moment(sim, 0.0_c_double, m0))
     s1 = s1 + m0
     s2 = s2 + m0 * m0
     call coag_sim_free(sim)
  end do
  call check_m0(2.0_c_double, "low-rank M0(2) within 6.07 SE of the exact value")

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
  ! every other binding
  call check(c_associated(coag_version()), "version")
  call check(c_associated(coag_status_name(COAG_INTERRUPTED)), "status names")
  call ok(coag_exact_density(COAG_EXACT_CONSTANT, 1_c_int64_t, 2.0_c_double, d))
  call check(abs(d - 0.25_c_double) < 1e-15_c_double, "exact density")
  call ok(coag_kernel_new_product(0.5_c_double, k2))
  call ok(coag_kernel_rate(k2, 4.0_c_double, 1.0_c_double, d))
  call check(abs(d - 2.0_c_double) < 1e-15_c_double, "product kernel rate")
  call coag_kernel_free(k2)
  call ok(coag_kernel_new_homogeneous(2.0_c_double, k2))
  call coag_kernel_free(k2)
  uk%rate = c_funloc(one_rate)
  uk%majorant = c_null_funptr
  uk%rank = 0
  uk%factors = c_null_funptr
  uk%low_rank_exact = 0
  uk%sup = c_funloc(one_sup)
  uk%user_data = c_null_ptr
  call ok(coag_kernel_new_user(uk, ku))
  uf%rate = c_funloc(frag_rate)
  uf%inverse_piece = c_funloc(frag_piece)
  uf%sup_rate = 1.0_c_double
  uf%user_data = c_null_ptr
  call ok(coag_fragmentation_new_user(uf, fu))
  ! acceptance-rejection under the user kernel: limits, pairs, clone, checkpoints
  call ok(coag_counts_default_config(lc, c_sizeof(lc)))
  lc%method = COAG_METHOD_REJECTION
  c2 = [2000_c_int64_t, 10_c_int64_t]
  call ok(coag_counts_new(lc, ku, c2, 2_c_size_t, sa))
  call ok(coag_sim_set_work_limit(sa, 100_c_int64_t))
  st = coag_sim_advance_to(sa, 1.0_c_double, rep)
  call check(st == COAG_INTERRUPTED, "work limit interrupts")
  call ok(coag_sim_set_work_limit(sa, 0_c_int64_t))
  call ok(coag_sim_advance_to(sa, 1.0_c_double, rep))
  call ok(coag_sim_totals(sa, rep))
  call check(rep%events > 0, "totals")
  call ok(coag_sim_occupied(sa, nocc))
  allocate(ps(nocc), pc(nocc))
  call ok(coag_sim_get_pairs(sa, ps, pc, nocc, vol, nw))
  call ok(coag_sim_particle_count(sa, np))
  call check(nw == nocc .and. sum(pc) == np .and. vol > 0, "pairs")
  call ok(coag_sim_clone(sa, sb))
  call ok(coag_sim_set_pairs(sb, ps, pc, nocc, vol))
  call ok(coag_sim_concentration(sa, 1.0_c_double, 1.0_c_double, d))
  call check(d > 0, "concentration")
  call ok(coag_sim_gel_mass(sa, d))
  call check(d > 0, "gel mass")
  call ok(coag_sim_checkpoint_size(sa, nck))
  allocate(ck(nck))
  call ok(coag_sim_checkpoint(sa, ck, nck, nw))
  call ok(coag_sim_restore(sb, ck, nw))
  ck(nw / 2) = ieor(ck(nw / 2), 1_c_int8_t)
  call check(coag_sim_restore(sb, ck, nw) == COAG_BAD_CHECKPOINT, "a corrupted checkpoint is refused")
  call ok(coag_sim_counts_config(sa, lc, c_sizeof(lc)))
  call check(lc%method == COAG_METHOD_REJECTION .and. abs(lc%volume - 2010.0_c_double) < 1e-12_c_double, &
       "counts config")
  call ok(coag_sim_set_time(sa, 5.0_c_double))
  call ok(coag_sim_reseed(sa, 3_c_int64_t, 0_c_int64_t))
  call ok(coag_sim_set_rng_callback(sa, c_funloc(rng_next), c_null_ptr))
  call ok(coag_sim_advance_to(sa, 5.5_c_double, rep))
  call ok(coag_sim_set_rng_callback(sa, c_null_funptr, c_null_ptr))
  call ok(coag_sim_set_counts(sa, c2, 2_c_size_t, 2010.0_c_double))
  call ok(coag_sim_time(sa, d))
  call check(abs(d - 5.5_c_double) < 1e-15_c_double, "time")
  call ok(coag_kernel_new_additive(1.0_c_double, k2))
  call ok(coag_sim_set_kernel(sa, k2))
  call coag_kernel_free(k2)
  call ok(coag_sim_state_len(sa, nw))
  deallocate(pc)
  allocate(pc(nw))
  call ok(coag_sim_get_counts(sa, pc, nw, vol))
  call check(sum(pc) == 2010, "dense counts")
  do st = 0, 3
     select case (st)
     case (0)
        call ok(coag_kernel_new_multiplicative(k2))
     case (1)
        call ok(coag_kernel_new_brownian(k2))
     case (2)
        call ok(coag_kernel_new_free_molecular(1.0_c_double, k2))
     case default
        call ok(coag_kernel_new_additive(0.0_c_double, k2))
     end select
     call ok(coag_kernel_rate(k2, 1.0_c_double, 2.0_c_double, d))
     call check(d > 0, "kernel rates")
     call coag_kernel_free(k2)
  end do
  call check(coag_kernel_new_constant(-1.0_c_double, k2) == COAG_INVALID_ARGUMENT, "a negative k0 is refused")
  call ok(coag_last_error_message(msgbuf, size(msgbuf, kind=c_size_t), nw))
  call check(nw > 0 .and. nw < size(msgbuf), "the message and its length")
  call coag_sim_free(sb)
  call coag_sim_free(sa)
  ! mass flow under the user fragmentation: setters, configuration, cancellation
  call ok(coag_massflow_new(mc, k, fu, sizes(1:64), 64_c_size_t, sm))
  call ok(coag_sim_set_dt(sm, 0.05_c_double))
  call ok(coag_sim_set_mass(sm, 2.0_c_double))
  call ok(coag_sim_set_fragmentation(sm, c_null_ptr))
  call ok(coag_sim_set_sizes(sm, sizes(1:64), 64_c_size_t))
  call ok(coag_sim_massflow_config(sm, mc2, c_sizeof(mc2)))
  call check(abs(mc2%dt - 0.05_c_double) < 1e-15_c_double .and. abs(mc2%mass - 2.0_c_double) < 1e-15_c_double, &
       "massflow config")
  call ok(coag_sim_set_cancel_callback(sm, c_funloc(cancel_now), c_null_ptr))
  call check(coag_sim_advance_to(sm, 10.0_c_double, rep) == COAG_INTERRUPTED, "cancelled")
  call ok(coag_sim_set_cancel_callback(sm, c_null_funptr, c_null_ptr))
  call coag_sim_free(sm)
  call coag_fragmentation_free(fu)
  call coag_kernel_free(ku)
  ! direct simulation over particles, event-driven: M0(1) of the constant kernel from
  ! 32 replicas within 6.07 standard errors of the exact value
  ones = 1.0_c_double
  s1 = 0
  s2 = 0
  do r = 1, reps
     call ok(coag_eventflow_default_config(ec, c_sizeof(ec)))
     ec%method = COAG_EVENTFLOW_DSA
     ec%seed = int(300 + r, c_int64_t)
     call ok(coag_eventflow_new(ec, k, c_null_ptr, ones, size(ones, kind=c_size_t), sm))
     call ok(coag_sim_advance_to(sm, 1.0_c_double, rep))
     call ok(coag_sim_moment(sm, 0.0_c_double, m0))
     if (r == 1) then
        call ok(coag_sim_eventflow_config(sm, ec2, c_sizeof(ec2)))
        call check(ec2%method == COAG_EVENTFLOW_DSA .and. ec2%capacity == size(ones), "eventflow config")
     end if
     s1 = s1 + m0
     s2 = s2 + m0 * m0
     call coag_sim_free(sm)
  end do
  call check_m0(1.0_c_double, "DSA M0(1) within 6.07 SE of the exact value")
  ! the same DSA in a workspace the caller owns runs bit for bit alike
  ec%seed = 301
  call ok(coag_eventflow_new(ec, k, c_null_ptr, ones, size(ones, kind=c_size_t), sm))
  call ok(coag_sim_advance_to(sm, 1.0_c_double, rep))
  call ok(coag_sim_moment(sm, 0.0_c_double, m0))
  call ok(coag_eventflow_workspace_size(ec, c_null_ptr, size(ones, kind=c_size_t), wbytes))
  allocate(ws(wbytes / 8))
  call ok(coag_eventflow_new_in(ec, k, c_null_ptr, ones, size(ones, kind=c_size_t), c_loc(ws), wbytes, sim2))
  call ok(coag_sim_advance_to(sim2, 1.0_c_double, rep))
  call ok(coag_sim_state_len(sm, nw))
  call ok(coag_sim_state_len(sim2, nocc))
  call check(nw == nocc, "eventflow workspace: the same number of particles")
  allocate(xa(nw), xb(nw))
  call ok(coag_sim_get_sizes(sm, xa, nw))
  call ok(coag_sim_get_sizes(sim2, xb, nw))
  call check(all(transfer(xa, 0_c_int64_t, size(xa)) == transfer(xb, 0_c_int64_t, size(xb))), &
       "eventflow workspace: the same sizes bit for bit")
  deallocate(xa, xb)
  call coag_sim_free(sim2)
  call coag_sim_free(sm)
  deallocate(ws)
  ! errors: a step back in time fails and names the problem
  call check(coag_sim_advance_to(sim, 0.5_c_double, rep) == COAG_TIME_BACKWARDS, "time backwards refused")
  call check(index(coag_error_message(), "before the current time") > 0, "error message")
  call coag_sim_free(sim)
  call coag_fragmentation_free(f)
  call coag_kernel_free(k)
  ! temperature-dependent MC: the model family (c = 1, gamma = 1/2) against its closed
  ! form over 32 replicas (Student t, 6.07 SE), then state, checkpoint and restore
  call ok(coag_thermal_model_exact(1.0_c_double, 0.5_c_double, 1.0_c_double, 1.0_c_double, &
       4.0_c_double, c_loc(tn_exact), c_loc(tt_exact)))
  s1 = 0.0_c_double
  s2 = 0.0_c_double
  do r = 1, reps
     call ok(coag_thermal_default_config(thc, c_sizeof(thc)))
     thc%kernel = COAG_THERMAL_MODEL
     thc%model_gamma = 0.5_c_double
     thc%seed = 41
     thc%stream = r
     call ok(coag_thermal_new(thc, [20000_c_int64_t], [1.0_c_double], 1_c_size_t, 20000.0_c_double, th))
     call ok(coag_thermal_advance_to(th, 4.0_c_double, c_null_ptr))
     call ok(coag_thermal_observe(th, 0.0_c_double, c_loc(tm), c_loc(tmean), c_null_ptr))
     s1 = s1 + tm
     s2 = s2 + tm * tm
     if (r < reps) call coag_thermal_free(th)
  end do
  mean = s1 / reps
  se = sqrt((s2 / reps - mean * mean) * reps / (reps - 1) / reps)
  call check(abs(mean - tn_exact) < 6.07_c_double * se, "thermal model N(4)")
  call ok(coag_thermal_info(th, c_loc(ttime), c_loc(tparts), c_loc(tvol), c_loc(tmax)))
  call check(abs(ttime - 4.0_c_double) < 1e-15_c_double .and. tparts > 0 .and. tvol > 0.0_c_double, &
       "thermal info")
  allocate(tcounts(tmax), ttemps(tmax))
  call ok(coag_thermal_state(th, c_loc(tcounts), c_loc(ttemps), tmax))
  call check(sum(tcounts) == tparts .and. all(ttemps >= 0.0_c_double), "thermal state")
  call ok(coag_thermal_checkpoint_size(th, tnck))
  allocate(tck(tnck))
  call ok(coag_thermal_save(th, tck, tnck, tnw))
  call ok(coag_thermal_advance_to(th, 6.0_c_double, c_null_ptr))
  call ok(coag_thermal_restore(th, tck, tnw))
  call ok(coag_thermal_info(th, c_loc(ttime), c_null_ptr, c_null_ptr, c_null_ptr))
  call check(abs(ttime - 4.0_c_double) < 1e-15_c_double, "thermal restore")
  call coag_thermal_free(th)
  ! DSMC: elastic collisions conserve momentum and energy; a checkpoint restores
  call ok(coag_dsmc_default_config(dsc, c_sizeof(dsc)))
  dsc%restitution = 1.0_c_double
  call ok(coag_dsmc_new_maxwellian(dsc, [300_c_int64_t, 100_c_int64_t], [1.0_c_double, 2.0_c_double], &
       2_c_size_t, 4000.0_c_double, ds))
  call ok(coag_dsmc_observe(ds, c_loc(dp0), c_loc(de0), c_null_ptr))
  call ok(coag_dsmc_advance_to(ds, 20.0_c_double, c_null_ptr))
  call ok(coag_dsmc_observe(ds, c_loc(dp1), c_loc(de1), c_null_ptr))
  call check(maxval(abs(dp1 - dp0)) < 1e-9_c_double .and. abs(de1 - de0) < 1e-12_c_double * de0, &
       "dsmc conservation")
  call ok(coag_dsmc_info(ds, c_loc(dtime), c_loc(dn), c_null_ptr))
  allocate(dsizes(dn), dvel(3 * dn))
  call ok(coag_dsmc_particles(ds, c_loc(dsizes), c_loc(dvel), int(dn, c_size_t)))
  call check(sum(dsizes) == 500 .and. dn == 400, "dsmc particles")
  call ok(coag_dsmc_checkpoint_size(ds, tnck))
  deallocate(tck)
  allocate(tck(tnck))
  call ok(coag_dsmc_save(ds, tck, tnck, tnw))
  call ok(coag_dsmc_advance_to(ds, 30.0_c_double, c_null_ptr))
  call ok(coag_dsmc_restore(ds, tck, tnw))
  call ok(coag_dsmc_info(ds, c_loc(dtime), c_null_ptr, c_null_ptr))
  call check(abs(dtime - 20.0_c_double) < 1e-15_c_double, "dsmc restore")
  call coag_dsmc_free(ds)
  call ok(coag_dsmc_new(dsc, [1_c_int64_t, 2_c_int64_t], [1.0_c_double, 0.0_c_double, 0.0_c_double, &
       -1.0_c_double, 0.0_c_double, 0.0_c_double], 2_c_size_t, 10.0_c_double, ds))
  call coag_dsmc_free(ds)
  ! Langevin batches: b = 0 outside the unit ball keeps E|U|^2 = |u0|^2 + 3 T (4.89 SE)
  call ok(coag_langevin_default_config(lgc, c_sizeof(lgc)))
  lgc%dim = 3
  lgc%radius = 1.0_c_double
  lgc%dt = 0.02_c_double
  call ok(coag_langevin_new(lgc, 20000_c_int64_t, [1.2_c_double, 0.0_c_double, 0.0_c_double], &
       [-2.0_c_double, 0.0_c_double, 0.0_c_double], 11_c_int64_t, 0_c_int64_t, lb))
  call ok(coag_langevin_advance_to(lb, 1.0_c_double, c_null_ptr))
  call ok(coag_langevin_mean(lb, c_funloc(u_squared), c_null_ptr, mean, se, c_null_ptr))
  call check(abs(mean - 7.0_c_double) < 4.89_c_double * se, "langevin E|U|^2 = |u0|^2 + 3T")
  call ok(coag_langevin_info(lb, c_loc(lt), c_loc(ldim), c_loc(ln)))
  call check(abs(lt - 1.0_c_double) < 1e-15_c_double .and. ldim == 3 .and. ln == 20000, "langevin info")
  allocate(lxs(3 * 20000), lhits(20000), lfirst(20000))
  call ok(coag_langevin_state(lb, c_loc(lxs), c_null_ptr, c_loc(lhits), c_loc(lfirst), 20000_c_size_t))
  call check(all(lxs(1::3)**2 + lxs(2::3)**2 + lxs(3::3)**2 >= 1.0_c_double - 1e-12_c_double), &
       "langevin positions outside the ball")
  call check(sum(lhits) > 1000 .and. minval(lfirst) > 0.0_c_double, "langevin hits")
  call ok(coag_langevin_checkpoint_size(lb, lnck))
  allocate(lck(lnck))
  call ok(coag_langevin_save(lb, lck, lnck, lnw))
  call ok(coag_langevin_advance_to(lb, 2.0_c_double, c_null_ptr))
  call ok(coag_langevin_restore(lb, lck, lnw))
  call ok(coag_langevin_info(lb, c_loc(lt), c_null_ptr, c_null_ptr))
  call check(abs(lt - 1.0_c_double) < 1e-15_c_double, "langevin restore")
  st = coag_langevin_advance_to(lb, 0.5_c_double, c_null_ptr)
  call check(st == COAG_TIME_BACKWARDS, "langevin time backwards")
  call coag_langevin_free(lb)
  ! a Fortran drift in caller memory (friction, far from the wall)
  call ok(coag_langevin_default_config(lgc, c_sizeof(lgc)))
  lgc%drift = COAG_DRIFT_CALLBACK
  lgc%drift_fn = c_funloc(friction_drift)
  call ok(coag_langevin_workspace_size(lgc, 1000_c_int64_t, lwb))
  allocate(lws(lwb / 8))
  call ok(coag_langevin_new_in(lgc, 1000_c_int64_t, [50.0_c_double], [0.5_c_double], 5_c_int64_t, &
       0_c_int64_t, c_loc(lws), lwb, lb))
  call ok(coag_langevin_advance_to(lb, 1.0_c_double, c_null_ptr))
  call ok(coag_langevin_mean(lb, c_null_funptr, c_null_ptr, mean, se, c_null_ptr))
  call check(abs(mean) < 1e-300_c_double, "no hits far from the wall")
  call coag_langevin_free(lb)
  ! the free-flight kernel from first hits: pi R^2 <|v|> (4.89 SE)
  fh%struct_size = c_sizeof(fh)
  fh%dim = 3
  fh%radius = 0.5_c_double
  fh%outer = 10.0_c_double
  fh%from = 0.4_c_double
  fh%to = 1.0_c_double
  fh%dt = 0.1_c_double
  fh%sigma = 0.0_c_double
  fh%velocity_sd = 1.0_c_double
  fh%trajectories = 100000
  fh%drift = COAG_DRIFT_ZERO
  fh%friction_rate = 0.0_c_double
  fh%drift_fn = c_null_funptr
  fh%drift_user_data = c_null_ptr
  call ok(coag_first_hit_kernel(fh, 7_c_int64_t, 0_c_int64_t, mean, se, lhitc))
  exact = acos(-1.0_c_double) * 0.25_c_double * sqrt(8.0_c_double / acos(-1.0_c_double))
  call check(abs(mean - exact) < 4.89_c_double * se .and. lhitc > 100, "free-flight kernel")

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

  ! the replicas' mean of M0 (sums s1, s2 of reps values) within 6.07 standard errors
  ! of the constant kernel's exact M0(t)
  subroutine check_m0(t, what)
    real(c_double), intent(in) :: t
    character(len=*), intent(in) :: what
    mean = s1 / reps
    se = sqrt((s2 / reps - mean * mean) / (reps - 1))
    call ok(coag_exact_moment(COAG_EXACT_CONSTANT, 0_c_int32_t, t, exact))
    call check(abs(mean - exact) < 6.072_c_double * se, what)
  end subroutine check_m0

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
