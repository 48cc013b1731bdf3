! Fortran client of libcoagula through include/coagula.f90, calling every function of the
! C ABI: the registry and core's tables; every scheme family through the one sim handle
! against exact solutions (32 replicas, 6.07 standard errors: Student t_31 at the suite's
! false-alarm rate 1e-6) — low-rank and direct-simulation M0 of the constant kernel, Lécot's
! coagulation-fragmentation test, the closed-form temperature model; a gas's conservation
! laws; Langevin batches (4.89 SE); checkpoints that continue bit for bit; refusals that
! leave the state unchanged.

program test_fortran
  use coagula
  use test_callbacks   ! (and its ieee_is_nan)
  implicit none
  integer, parameter :: reps = 32
  real(c_double), parameter :: tol32 = 6.07_c_double, zl = 4.89_c_double
  integer :: nfail = 0, nchecks = 0

  call test_tables()
  call test_lowrank_and_options()
  call test_massflow()
  call test_user_kernel_counts()
  call test_dsa()
  call test_temperature()
  call test_gas()
  call test_processes()
  call test_sectional()
  call test_langevin()
  print '(a, i0, a, i0, a)', "test_fortran: ", nchecks - nfail, " passed, ", nfail, " failed"
  if (nfail /= 0) stop 1

contains

  subroutine ok(status)
    integer(c_int32_t), intent(in) :: status
    nchecks = nchecks + 1
    if (status /= COAG_OK) then
       print *, "call failed: ", coag_string(coag_status_name(status)), ": ", coag_error_message()
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

  ! a status that must be `want`
  subroutine expect(status, want, what)
    integer(c_int32_t), intent(in) :: status, want
    character(len=*), intent(in) :: what
    call check(status == want, what // ": got " // coag_string(coag_status_name(status)) // ", expected " // &
         coag_string(coag_status_name(want)))
  end subroutine expect
  ! bitwise equality of reals (bit-for-bit checks, exact values)
  elemental logical function same(a, b)
    real(c_double), intent(in) :: a, b
    same = transfer(a, 0_c_int64_t) == transfer(b, 0_c_int64_t)
  end function same
  ! whether a sim's checkpoint (state, own stream, settings) is `bytes`
  logical function sim_is(sim, bytes)
    type(c_ptr), intent(in) :: sim
    integer(c_int8_t), intent(in) :: bytes(:)
    integer(c_int8_t), allocatable :: x(:)
    x = snapshot(sim)
    sim_is = size(x) == size(bytes)
    if (sim_is) sim_is = all(x == bytes)
  end function sim_is
  ! a NUL-terminated copy of s
  function cs(s)
    character(len=*), intent(in) :: s
    character(kind=c_char, len=len(s) + 1) :: cs
    cs = s // c_null_char
  end function cs
  ! the replicas' mean within tol32 standard errors of `exact`
  subroutine check_mean(x, exact, what)
    real(c_double), intent(in) :: x(:), exact
    character(len=*), intent(in) :: what
    real(c_double) :: m, se
    character(len=80) :: line
    m = sum(x) / size(x)
    se = sqrt(sum((x - m)**2) / (size(x) - 1) / size(x))
    write (line, '(3(a, es12.5))') " ", m, " +- ", se, " vs ", exact
    call check(abs(m - exact) < tol32 * se .and. se > 0, what // trim(line))
  end subroutine check_mean

  function kernel(name, params) result(k)
    character(len=*), intent(in) :: name
    real(c_double), intent(in) :: params(:)
    type(c_ptr) :: k
    call ok(coag_kernel_new(cs(name), params, size(params, kind=c_size_t), k))
  end function kernel

  function seeded(seed, stream) result(o)
    integer, intent(in) :: seed, stream
    type(c_ptr) :: o
    call ok(coag_options_new(o))
    call ok(coag_options_set_count(o, cs("seed"), int(seed, c_int64_t)))
    call ok(coag_options_set_count(o, cs("stream"), int(stream, c_int64_t)))
  end function seeded

  ! a sim's checkpoint
  function snapshot(sim) result(buf)
    type(c_ptr), intent(in) :: sim
    integer(c_int8_t), allocatable :: buf(:)
    integer(c_size_t), target :: n, written
    call ok(coag_sim_checkpoint_size(sim, n))
    allocate(buf(n))
    call ok(coag_sim_checkpoint(sim, buf, n, c_loc(written)))
    buf = buf(1:written)
  end function snapshot

  ! the registry and core's tables; the structs' sizes are those of the C header (LP64)
  subroutine test_tables()
    type(coag_scheme_info) :: si
    type(coag_option_info) :: oi
    type(coag_builtin_info) :: bi
    type(coag_param_info) :: pi
    type(coag_step_report) :: rep
    type(c_ptr) :: p, k
    character(len=:), allocatable :: name
    character(len=16), parameter :: required(6) = [character(len=16) :: "a", "gamma", "temperature", &
         "viscosity", "density", "monomer-diameter"]
    real(c_double), parameter :: values(6) = [0.5_c_double, 1.5_c_double, 300.0_c_double, 1.8e-5_c_double, &
         1000.0_c_double, 3e-10_c_double]
    integer :: m, k6
    integer(c_size_t) :: n, i, j, idx
    integer(c_int32_t) :: st
    real(c_double) :: params(3), v
    call check(c_sizeof(si) == 80 .and. c_sizeof(oi) == 40 .and. c_sizeof(bi) == 56 .and. c_sizeof(pi) == 48 .and. &
         c_sizeof(rep) == 80, "struct sizes as in coagula.h")
    call check(len(coag_string(coag_version())) > 0, "version")
    call check(coag_string(coag_status_name(COAG_REENTRANT)) == "COAG_REENTRANT", "status name")
    call check(coag_string(coag_status_name(999_c_int32_t)) == "COAG_UNKNOWN", "unknown status name")
    call ok(coag_scheme_count(n))
    call check(n >= 14, "schemes")
    do i = 0, n - 1
       call ok(coag_scheme_info_get(i, si, c_sizeof(si)))
       name = coag_string(si%name)
       call ok(coag_scheme_find(cs(name), idx))
       call check(idx == i .and. si%inits /= 0 .and. si%tag > 0, "scheme " // name // " found")
       call check(len(coag_string(si%paper)) > 0, name // " paper")
       call check(len(coag_string(si%summary)) > 0, name // " summary")
       do j = 0, si%option_count - 1
          call ok(coag_scheme_option(i, j, p))
          call check(len(coag_string(p)) > 0, "scheme option")
       end do
       do j = 0, si%observable_count - 1
          call ok(coag_scheme_observable(i, j, p))
          call check(len(coag_string(p)) > 0, "scheme observable")
       end do
       call expect(coag_scheme_option(i, si%option_count, p), COAG_INVALID_ARGUMENT, "option past the count")
    end do
    call ok(coag_scheme_find(cs("dsmc"), idx))
    call ok(coag_scheme_info_get(idx, si, c_sizeof(si)))
    call check(si%model == COAG_MODEL_GAS .and. si%inits == COAG_INIT_VELOCITIES .and. si%sizes == COAG_SAMPLES_NONE &
         .and. si%fragmentation == 0 .and. si%memory == COAG_MEMORY_GROWING .and. si%law == COAG_LAW_GAS .and. &
         si%option_count == 1 .and. si%observable_count == 5, "dsmc capabilities")
    call expect(coag_scheme_find(cs("no-such-scheme"), idx), COAG_INVALID_ARGUMENT, "unknown scheme")
    call check(index(coag_error_message(), "lowrank") > 0, "the message lists the schemes")
    call ok(coag_option_count(n))
    call check(n >= 15, "option keys")
    do i = 0, n - 1
       call ok(coag_option_info_get(i, oi, c_sizeof(oi)))
       name = coag_string(oi%name)
       if (name == "seed") call check(oi%kind == COAG_OPTION_KIND_COUNT .and. oi%must_match == 0, "seed")
       if (name == "dt") call check(oi%kind == COAG_OPTION_REAL .and. oi%must_match /= 0, "dt")
       if (name == "dt") call check(coag_string(oi%default_value) == "0.01", "dt's default")
       if (name == "points") call check(oi%kind == COAG_OPTION_NAME, "points")
       if (name == "batched-clock") call check(oi%kind == COAG_OPTION_FLAG, "batched-clock")
    end do
    ! every built-in kernel from its defaults and a valid value for each required parameter
    call ok(coag_builtin_count(n))
    call check(n >= 12, "builtins")
    do i = 0, n - 1
       call ok(coag_builtin_info_get(i, bi, c_sizeof(bi)))
       do j = 0, bi%param_count - 1
          call ok(coag_builtin_param(i, j, pi, c_sizeof(pi)))
          params(j + 1) = pi%default_value
          if (pi%has_default == 0) then
             call check(ieee_is_nan(pi%default_value), "a required parameter's default is NaN")
             m = findloc([(required(k6) == coag_string(pi%name), k6 = 1, 6)], .true., 1)
             call check(m > 0, "no test value for " // coag_string(pi%name))
             if (m > 0) params(j + 1) = values(m)
          end if
       end do
       call ok(coag_kernel_new(cs(coag_string(bi%name)), params, bi%param_count, k))
       st = coag_kernel_rate(k, 2.0_c_double, 3.0_c_double, v)
       call expect(st, merge(COAG_OK, COAG_UNSUPPORTED, bi%family == COAG_FAMILY_COAGULATION), "K(2, 3) of " // &
            coag_string(bi%name))
       if (st == COAG_OK) call check(v > 0, "K(2, 3) > 0 for " // coag_string(bi%name))
       call coag_kernel_free(k)
    end do
    k = kernel("product", [0.5_c_double])
    call ok(coag_kernel_rate(k, 4.0_c_double, 9.0_c_double, v))
    call check(same(v, 6.0_c_double), "product kernel (4 * 9)^0.5")
    call coag_kernel_free(k)
    call expect(coag_kernel_new(cs("constant"), [-1.0_c_double], 1_c_size_t, k), COAG_INVALID_ARGUMENT, "negative b")
    call check(index(coag_error_message(), "coefficient") > 0, "the message names the coefficient")
    call expect(coag_kernel_new(cs("product"), params, 0_c_size_t, k), COAG_INVALID_ARGUMENT, "a missing parameter")
    call ok(coag_exact_density(COAG_EXACT_CONSTANT, 1_c_int64_t, 2.0_c_double, v))
    call check(abs(v - 0.25_c_double) < 1e-15_c_double, "exact n_1(2) = 1/4")
    call ok(coag_step_report_init(rep, c_sizeof(rep)))
    call check(rep%struct_size == c_sizeof(rep) .and. rep%events == 0, "report init")
  end subroutine test_tables

  ! Marcus–Lushnikov with K = 1 from 8192 monomers: M0(2) = 1/2; options, and an option
  ! the scheme does not take
  subroutine test_lowrank_and_options()
    type(c_ptr) :: k, o, o2, sim, p
    real(c_double) :: m0(reps), exact
    integer :: r, h
    k = kernel("constant", [1.0_c_double])
    do r = 1, reps
       o = seeded(100 + r, 0)
       call ok(coag_sim_new_counts(cs("lowrank"), k, c_null_ptr, o, [8192_c_int64_t], 1_c_size_t, 8192.0_c_double, sim))
       call coag_options_free(o)
       if (r == 1) then
          call ok(coag_sim_scheme(sim, p))
          call check(coag_string(p) == "lowrank", "scheme name")
          call ok(coag_sim_engine(sim, p))
          call check(coag_string(p) == "counted", "8192 particles run on the counted engine")
       end if
       do h = 1, 10
          call ok(coag_sim_advance_to(sim, 0.2_c_double * h, c_null_ptr))
       end do
       call ok(coag_sim_moment(sim, 0.0_c_double, m0(r)))
       call coag_sim_free(sim)
    end do
    call ok(coag_exact_moment(COAG_EXACT_CONSTANT, 0_c_int32_t, 2.0_c_double, exact))
    call check(same(exact, 0.5_c_double), "exact M0(2) = 1/2")
    call check_mean(m0, exact, "low-rank M0(2)")
    ! options: kinds, refusals, a clone, a key the scheme does not take
    call ok(coag_options_new(o))
    call ok(coag_options_set_real(o, cs("dt"), 0.05_c_double))
    call ok(coag_options_set_flag(o, cs("batched-clock"), 0_c_int32_t))
    call ok(coag_options_set_name(o, cs("engine"), cs("slots")))
    call ok(coag_options_set_real(o, cs("size-limit"), 1e6_c_double))
    call expect(coag_options_set_real(o, cs("no-such-key"), 1.0_c_double), COAG_INVALID_ARGUMENT, "unknown key")
    call expect(coag_options_set_name(o, cs("points"), cs("qmc")), COAG_INVALID_ARGUMENT, "unknown points")
    call expect(coag_options_set_real(o, cs("dt"), -1.0_c_double), COAG_INVALID_ARGUMENT, "negative dt")
    call expect(coag_options_set_count(o, cs("engine"), 1_c_int64_t), COAG_INVALID_ARGUMENT, "a count for a name")
    call ok(coag_options_clone(o, o2))
    call coag_options_free(o)
    sim = c_null_ptr
    call expect(coag_sim_new_counts(cs("lowrank"), k, c_null_ptr, o2, [100_c_int64_t], 1_c_size_t, 100.0_c_double, &
         sim), COAG_UNSUPPORTED, "dt on lowrank")
    call check(index(coag_error_message(), "dt") > 0 .and. .not. c_associated(sim), "the message names dt")
    call coag_options_free(o2)
    call coag_kernel_free(k)
  end subroutine test_lowrank_and_options

  ! Lécot's coagulation–fragmentation test with QMC points (M2(1) within 5e-3), the same
  ! run in caller memory bit for bit, what a host changes, cancellation, re-entry
  subroutine test_massflow()
    integer, parameter :: n = 4096
    type(c_ptr) :: k, f, fu, sim, sim2, sm
    type(coag_step_report), target :: rep
    type(coag_user_fragmentation) :: uf
    real(c_double), target :: fd(2)
    integer(c_int32_t), target :: polls(2)
    real(c_double) :: sizes(n), m2, m2b, exact, t
    real(c_double), allocatable, target :: ws(:)
    integer(c_size_t) :: wbytes
    integer(c_size_t), target :: nmsg, nw
    character(kind=c_char), target :: small(5)
    character(len=:), allocatable :: msg
    integer(c_int8_t), allocatable :: before(:)
    k = kernel("constant", [1.0_c_double])
    call ok(coag_fragmentation_new_binary_uniform(1.0_c_double, f))
    sizes = 1
    call ok(coag_sim_new_sizes(cs("massflow"), k, f, c_null_ptr, sizes, size(sizes, kind=c_size_t), 1.0_c_double, sim))
    call ok(coag_step_report_init(rep, c_sizeof(rep)))
    call ok(coag_sim_advance_to(sim, 1.0_c_double, c_loc(rep)))
    call ok(coag_sim_moment(sim, 2.0_c_double, m2))
    call ok(coag_exact_moment(COAG_EXACT_COAG_FRAG, 2_c_int32_t, 1.0_c_double, exact))
    call check(abs(m2 - exact) < 5e-3_c_double, "mass-flow M2(1) close to the exact value")
    call check(rep%proposals == 100 * n .and. same(rep%time, 1.0_c_double), "one proposal per particle and step")
    call ok(coag_sim_get_sizes(sim, sizes, size(sizes, kind=c_size_t)))
    call check(all(sizes(2:) >= sizes(:n - 1)), "sizes come back sorted")
    call expect(coag_sim_workspace_size(cs("lowrank"), c_null_ptr, c_null_ptr, 10_c_size_t, wbytes), &
         COAG_UNSUPPORTED, "no workspace for a growing scheme")
    call ok(coag_sim_workspace_size(cs("massflow"), f, c_null_ptr, size(sizes, kind=c_size_t), wbytes))
    call check(wbytes == 6 * 8 * n, "workspace of 6 N doubles")
    allocate(ws(wbytes / 8))
    sizes = 1
    call ok(coag_sim_new_sizes_in(cs("massflow"), k, f, c_null_ptr, sizes, size(sizes, kind=c_size_t), 1.0_c_double, &
         c_loc(ws), wbytes, sim2))
    call ok(coag_sim_advance_to(sim2, 1.0_c_double, c_null_ptr))
    call ok(coag_sim_moment(sim2, 2.0_c_double, m2b))
    call check(same(m2b, m2), "caller workspace: the same M2 bit for bit")
    call check(sim_is(sim2, snapshot(sim)), "caller workspace: the same checkpoint")
    call coag_sim_free(sim2)
    ! errors: a step back in time, named; the sim unchanged
    before = snapshot(sim)
    call expect(coag_sim_advance_to(sim, 0.5_c_double, c_null_ptr), COAG_TIME_BACKWARDS, "time backwards")
    msg = coag_error_message()
    call check(index(msg, "before the current time") > 0, "error message")
    call ok(coag_last_error_message(c_null_ptr, 0_c_size_t, c_loc(nmsg)))
    call expect(coag_last_error_message(c_loc(small), 5_c_size_t, c_loc(nw)), COAG_BUFFER_TOO_SMALL, "a short buffer")
    call check(nw == nmsg .and. nmsg == len(msg) .and. small(5) == c_null_char, "the message's length, a short buffer")
    call check(coag_string(c_loc(small)) == msg(1:4), "the message truncated to the buffer")
    call expect(coag_sim_set_dt(sim, -1.0_c_double), COAG_INVALID_ARGUMENT, "negative dt")
    call expect(coag_sim_set_mass(sim, 0.0_c_double), COAG_INVALID_ARGUMENT, "zero mass")
    call expect(coag_sim_set_counts(sim, [1_c_int64_t], 1_c_size_t, 1.0_c_double), COAG_UNSUPPORTED, "counts")
    call check(sim_is(sim, before), "refusals changed the mass-flow sim")
    call coag_sim_free(sim)
    ! under a user fragmentation: setters, cancellation, a callback calling back in
    fd = [1, 0]
    uf = coag_user_fragmentation(c_funloc(frag_rate), c_funloc(frag_piece), 1.0_c_double, c_loc(fd))
    call check(c_sizeof(uf) == 32, "coag_user_fragmentation's size as in coagula.h")
    call ok(coag_fragmentation_new_user(uf, fu))
    call ok(coag_sim_new_sizes(cs("massflow"), k, fu, c_null_ptr, sizes(1:1024), 1024_c_size_t, 1.0_c_double, sm))
    call ok(coag_sim_advance_to(sm, 1.0_c_double, c_null_ptr))
    call ok(coag_sim_moment(sm, 2.0_c_double, m2))
    call check(abs(m2 - exact) < 0.02_c_double .and. fd(2) > 0, "user fragmentation: M2(1)")
    call ok(coag_sim_set_dt(sm, 0.05_c_double))
    call ok(coag_sim_set_mass(sm, 2.0_c_double))
    call ok(coag_sim_moment(sm, 1.0_c_double, m2))
    call check(abs(m2 - 2) < 1e-12_c_double, "set_mass: M1 = 2")
    call ok(coag_sim_set_fragmentation(sm, c_null_ptr))
    sizes = 3
    call ok(coag_sim_set_sizes(sm, sizes(1:1024), 1024_c_size_t))
    call ok(coag_sim_get_sizes(sm, sizes(1:1024), 1024_c_size_t))
    call check(all(same(sizes(1:1024), 3.0_c_double)), "set_sizes")
    call ok(coag_sim_set_time(sm, 5.0_c_double))
    polls = [0, 3]
    call ok(coag_sim_set_cancel_callback(sm, c_funloc(cancel_at), c_loc(polls)))
    call expect(coag_sim_advance_to(sm, 10.0_c_double, c_null_ptr), COAG_INTERRUPTED, "cancelled")
    call ok(coag_sim_time(sm, t))
    call check(polls(1) == 3 .and. t > 5 .and. t < 10, "set_time; cancelled at the third poll")
    call ok(coag_sim_set_cancel_callback(sm, c_funloc(call_back_in), sm))
    call ok(coag_sim_advance_to(sm, 10.0_c_double, c_null_ptr))
    call expect(reentry_status, COAG_REENTRANT, "a callback calling back into its sim")
    call ok(coag_sim_set_cancel_callback(sm, c_null_funptr, c_null_ptr))
    call ok(coag_step_report_init(rep, c_sizeof(rep)))
    call ok(coag_sim_advance_to(sm, 10.5_c_double, c_loc(rep)))
    call check(rep%proposals == 10 * 1024, "set_dt 0.05 (10 steps of 0.05), kept after the refused call")
    call coag_sim_free(sm)
    call coag_fragmentation_free(fu)
    call coag_fragmentation_free(f)
    call coag_kernel_free(k)
  end subroutine test_massflow

  ! acceptance–rejection under a user kernel K = 1 (rank 1, exact): bounded calls,
  ! pairs, a clone and a checkpoint that continue bit for bit, a host random stream,
  ! a stuck one undone, a corrupted checkpoint and a negative rate refused unchanged
  subroutine test_user_kernel_counts()
    type(coag_user_kernel) :: uk
    type(c_ptr) :: ku, k2, sa, sb
    real(c_double), target :: k0, vol, d, t
    real(c_double) :: cls(2)
    integer(c_int64_t), target :: state, calls, np
    integer(c_int64_t), allocatable :: ps(:), pc(:), ca(:), cb(:)
    integer(c_int8_t), allocatable :: ck(:), before(:)
    integer(c_size_t), target :: nocc, nw
    type(coag_step_report) :: tot
    k0 = 1
    uk = coag_user_kernel(c_funloc(user_rate), c_null_funptr, 1, c_funloc(user_factors), 1, c_funloc(user_sup), c_loc(k0))
    call check(c_sizeof(uk) == 56, "coag_user_kernel's size as in coagula.h")
    call ok(coag_kernel_new_user(uk, ku))
    call ok(coag_kernel_rate(ku, 2.0_c_double, 3.0_c_double, d))
    call check(same(d, 1.0_c_double), "user kernel rate")
    uk%rank = 9
    call expect(coag_kernel_new_user(uk, k2), COAG_INVALID_ARGUMENT, "rank above 8")
    call ok(coag_sim_new_counts(cs("rejection"), ku, c_null_ptr, c_null_ptr, [2000_c_int64_t, 10_c_int64_t], &
         2_c_size_t, 2010.0_c_double, sa))
    call ok(coag_sim_set_work_limit(sa, 100_c_int64_t))
    call expect(coag_sim_advance_to(sa, 1.0_c_double, c_null_ptr), COAG_INTERRUPTED, "work limit interrupts")
    call ok(coag_sim_set_work_limit(sa, 0_c_int64_t))
    call ok(coag_sim_advance_to(sa, 1.0_c_double, c_null_ptr))
    call ok(coag_step_report_init(tot, c_sizeof(tot)))
    call ok(coag_sim_totals(sa, tot))
    call check(tot%events > 0 .and. same(tot%time, 1.0_c_double) .and. tot%bound_violations == 0, "totals")
    call ok(coag_sim_occupied(sa, nocc))
    allocate(ps(nocc), pc(nocc))
    call ok(coag_sim_get_pairs(sa, ps, pc, nocc, c_loc(vol), c_loc(nw)))
    call ok(coag_sim_particle_count(sa, np))
    call check(nw == nocc .and. sum(pc) == np .and. sum(ps * pc) == 2020 .and. same(vol, 2010.0_c_double), "pairs")
    call expect(coag_sim_get_pairs(sa, ps, pc, nocc - 1, c_null_ptr, c_null_ptr), COAG_BUFFER_TOO_SMALL, "short pairs")
    call ok(coag_sim_concentration(sa, 1.0_c_double, 1.0_c_double, d))
    call check(abs(d - pc(1) / vol) < 1e-15_c_double .and. ps(1) == 1, "concentration of monomers")
    call ok(coag_sim_class_concentrations(sa, [1.0_c_double, 2.0_c_double, 1e9_c_double], 3_c_size_t, cls))
    call check(abs(cls(1) - pc(1) / vol) + abs(cls(1) + cls(2) - np / vol) < 1e-12_c_double, "classes [1,2), [2,1e9)")
    call ok(coag_sim_gel_mass(sa, d))
    call check(abs(d - ps(nocc) / vol) < 1e-15_c_double, "gel mass: the largest cluster per volume")
    ! a clone, a checkpoint restored into it and the run itself continue alike
    call ok(coag_sim_clone(sa, sb))
    ck = snapshot(sa)
    call ok(coag_sim_advance_to(sa, 2.0_c_double, c_null_ptr))
    call ok(coag_sim_advance_to(sb, 2.0_c_double, c_null_ptr))
    call check(sim_is(sa, snapshot(sb)), "clone continues bit for bit")
    call ok(coag_sim_restore(sb, ck, size(ck, kind=c_size_t)))
    call ok(coag_sim_advance_to(sb, 2.0_c_double, c_null_ptr))
    call check(sim_is(sa, snapshot(sb)), "restored run continues bit for bit")
    ck(size(ck) / 2) = ieor(ck(size(ck) / 2), 1_c_int8_t)
    before = snapshot(sb)
    call expect(coag_sim_restore(sb, ck, size(ck, kind=c_size_t)), COAG_BAD_CHECKPOINT, "corrupted checkpoint")
    call check(sim_is(sb, before), "a refused restore changed the sim")
    ! set_pairs and set_counts give back the state; dense counts
    call ok(coag_sim_set_pairs(sb, ps, pc, nocc, vol))
    call ok(coag_sim_state_len(sb, nw))
    allocate(ca(4096), cb(4096))   ! (past the state's length: zeroed)
    call ok(coag_sim_get_counts(sb, ca, size(ca, kind=c_size_t), c_loc(vol)))
    call check(nw == ps(nocc) .and. all(ca(ps) == pc) .and. sum(ca) == np .and. same(vol, 2010.0_c_double), "set_pairs")
    call ok(coag_sim_set_counts(sb, ca, nw, 2010.0_c_double))
    call ok(coag_sim_get_counts(sb, cb, size(cb, kind=c_size_t), c_null_ptr))
    call check(all(ca == cb), "set_counts")
    ! a host random stream: the same stream gives the same run
    call coag_sim_free(sa)
    call ok(coag_sim_clone(sb, sa))
    state = 88172645463325252_c_int64_t
    call ok(coag_sim_set_rng_callback(sa, c_funloc(rng_next), c_loc(state)))
    call ok(coag_sim_advance_to(sa, 3.0_c_double, c_null_ptr))
    state = 88172645463325252_c_int64_t
    call ok(coag_sim_set_rng_callback(sb, c_funloc(rng_next), c_loc(state)))
    call ok(coag_sim_advance_to(sb, 3.0_c_double, c_null_ptr))
    call check(sim_is(sa, snapshot(sb)), "the same host stream, the same run")
    calls = 0
    before = snapshot(sb)
    call ok(coag_sim_set_rng_callback(sb, c_funloc(rng_stuck), c_loc(calls)))
    call expect(coag_sim_advance_to(sb, 4.0_c_double, c_null_ptr), COAG_RNG_FAILURE, "a stuck host stream")
    call check(calls >= 8, "the stuck stream was called")
    call check(sim_is(sb, before), "a stuck stream's call undone")
    call ok(coag_sim_set_rng_callback(sb, c_null_funptr, c_null_ptr))
    call ok(coag_sim_reseed(sb, 3_c_int64_t, 1_c_int64_t))
    call ok(coag_sim_advance_to(sb, 4.0_c_double, c_null_ptr))
    ! a negative rate at run time: COAG_INVALID_RATE, the state as it was
    call ok(coag_sim_get_counts(sb, cb, size(cb, kind=c_size_t), c_null_ptr))
    call ok(coag_sim_time(sb, t))
    k0 = -1
    call expect(coag_sim_advance_to(sb, 5.0_c_double, c_null_ptr), COAG_INVALID_RATE, "a negative rate")
    call ok(coag_sim_get_counts(sb, ca, size(ca, kind=c_size_t), c_null_ptr))
    call ok(coag_sim_time(sb, d))
    call check(all(ca == cb) .and. same(d, t), "a refused event changed the sim")
    k0 = 1
    ! a built-in kernel in place of the user's
    k2 = kernel("additive", [1.0_c_double])
    call ok(coag_sim_set_kernel(sb, k2))
    call coag_kernel_free(k2)
    call ok(coag_sim_advance_to(sb, 4.5_c_double, c_null_ptr))
    call ok(coag_sim_moment(sb, 1.0_c_double, d))
    call check(abs(d - 2020 / 2010.0_c_double) < 1e-12_c_double, "mass conserved: M1")
    call coag_sim_free(sb)
    call coag_sim_free(sa)
    call ok(coag_kernel_set_user_blocks(ku, c_funloc(user_block_sup), 1))  ! (runs: tests/c/test_schemes.c)
    call expect(coag_kernel_set_user_blocks(c_null_ptr, c_null_funptr, 0), COAG_NULL_PARAMETER, "NULL kernel")
    call coag_kernel_free(ku)
  end subroutine test_user_kernel_counts

  ! direct simulation over 2048 particles, event-driven: M0(1) of the constant kernel;
  ! the same run in caller memory bit for bit
  subroutine test_dsa()
    type(c_ptr) :: k, o, sm, sim1, sim2
    real(c_double) :: ones(2048), m0(reps), exact
    real(c_double), allocatable, target :: ws(:)
    integer(c_size_t) :: wbytes
    integer :: r
    k = kernel("constant", [1.0_c_double])
    ones = 1
    sim1 = c_null_ptr
    do r = 1, reps
       o = seeded(300 + r, 0)
       call ok(coag_sim_new_sizes(cs("dsa"), k, c_null_ptr, o, ones, size(ones, kind=c_size_t), 1.0_c_double, sm))
       call coag_options_free(o)
       call ok(coag_sim_advance_to(sm, 1.0_c_double, c_null_ptr))
       call ok(coag_sim_moment(sm, 0.0_c_double, m0(r)))
       if (r > 1) call coag_sim_free(sm)
       if (r == 1) sim1 = sm
    end do
    call ok(coag_exact_moment(COAG_EXACT_CONSTANT, 0_c_int32_t, 1.0_c_double, exact))
    call check_mean(m0, exact, "DSA M0(1)")
    o = seeded(301, 0)
    call ok(coag_sim_workspace_size(cs("dsa"), c_null_ptr, o, size(ones, kind=c_size_t), wbytes))
    allocate(ws(wbytes / 8))
    call ok(coag_sim_new_sizes_in(cs("dsa"), k, c_null_ptr, o, ones, size(ones, kind=c_size_t), 1.0_c_double, &
         c_loc(ws), wbytes, sim2))
    call coag_options_free(o)
    call ok(coag_sim_advance_to(sim2, 1.0_c_double, c_null_ptr))
    call check(sim_is(sim2, snapshot(sim1)), "DSA workspace: the same run bit for bit")
    call coag_sim_free(sim2)
    call coag_sim_free(sim1)
    call coag_kernel_free(k)
  end subroutine test_dsa

  ! the closed-form temperature model (c = 1, gamma = 1/2; TEMPERATURE.md, core's
  ! ClosedFormSolution): from n_1(0) = 1, T_1(0) = 1, u = [1 + (1+g) c t / 2]^(1/(1+g)),
  ! N = 1/u, mean temperature u^(1-2g); per-size temperatures, a checkpoint
  subroutine test_temperature()
    real(c_double), parameter :: c = 1, g = 0.5_c_double, t = 4
    type(c_ptr) :: tk, o, th, tb
    real(c_double) :: u, n(reps), temp(reps), e0, v
    integer(c_int64_t) :: sz(2)
    real(c_double) :: vals(2)
    integer(c_size_t), target :: nw
    integer(c_int8_t), allocatable :: ck(:)
    integer :: r
    u = (1 + (1 + g) * c * t / 2)**(1 / (1 + g))
    tk = kernel("temperature-closed-form", [c, g])
    do r = 1, reps
       o = seeded(41, r)
       call ok(coag_sim_new_temperatures(cs("temperature"), tk, o, [20000_c_int64_t], [1.0_c_double], 1_c_size_t, &
            20000.0_c_double, th))
       call coag_options_free(o)
       call ok(coag_sim_advance_to(th, t, c_null_ptr))
       call ok(coag_sim_moment(th, 0.0_c_double, n(r)))
       call ok(coag_sim_observable(th, cs("mean-temperature"), temp(r)))
       call coag_sim_free(th)
    end do
    call check_mean(n, 1 / u, "temperature model N(4)")
    call check_mean(temp, u**(1 - 2 * g), "temperature model mean T(4)")
    call ok(coag_sim_new_temperatures(cs("temperature-rejection"), tk, c_null_ptr, [3000_c_int64_t, 200_c_int64_t], &
         [1.0_c_double, 1.5_c_double], 2_c_size_t, 30000.0_c_double, th))
    call ok(coag_sim_size_values(th, cs("temperature"), sz, vals, 2_c_size_t, c_loc(nw)))
    call check(nw == 2 .and. all(sz == [1, 2]) .and. all(same(vals, [1.0_c_double, 1.5_c_double])), &
         "partial temperatures")
    call expect(coag_sim_size_values(th, cs("temperature"), sz, vals, 1_c_size_t, c_null_ptr), COAG_BUFFER_TOO_SMALL, &
         "short buffers")
    call expect(coag_sim_observable(th, cs("no-such-observable"), v), COAG_UNSUPPORTED, "unknown observable")
    call ok(coag_sim_observable(th, cs("energy"), e0))
    call check(e0 > 0, "energy")
    call ok(coag_sim_advance_to(th, 2.0_c_double, c_null_ptr))
    ck = snapshot(th)
    call ok(coag_sim_clone(th, tb))
    call ok(coag_sim_advance_to(tb, 4.0_c_double, c_null_ptr))
    call ok(coag_sim_restore(th, ck, size(ck, kind=c_size_t)))
    call ok(coag_sim_advance_to(th, 4.0_c_double, c_null_ptr))
    call check(sim_is(tb, snapshot(th)), "temperature checkpoint continues bit for bit")
    call coag_sim_free(tb)
    call coag_sim_free(th)
    call coag_kernel_free(tk)
  end subroutine test_temperature

  ! hard spheres with restitution 1: elastic collisions conserve momentum and energy;
  ! particles given are read back; a checkpoint continues bit for bit
  ! a monomer source, dilution and growth by attachment on lowrank: the books balance
  subroutine test_processes()
    type(c_ptr) :: k, o, sim
    type(coag_books) :: b
    integer(c_int64_t) :: n
    real(c_double) :: m0, m1, v, x(7), cn(7), cn2(7), rates(7), outside(4)
    real(c_double), target :: rk = 0.3_c_double
    k = kernel("constant", [1.0_c_double])
    o = seeded(3, 0)
    call ok(coag_sim_new_counts(cs("lowrank"), k, c_null_ptr, o, [1000_c_int64_t], 1_c_size_t, &
         1000.0_c_double, sim))
    call coag_options_free(o)
    call ok(coag_sim_set_source(sim, 0.5_c_double, COAG_SOURCE_MONODISPERSE, 1.0_c_double, 0.0_c_double))
    call ok(coag_sim_set_removal(sim, 0.2_c_double, 0.0_c_double))
    call ok(coag_sim_set_growth_step(sim, 0.25_c_double)) ! (not used on integer sizes; see test_processes.c)
    call ok(coag_sim_set_growth(sim, 0.1_c_double, 1.0_c_double))
    call expect(coag_sim_set_removal(sim, 1.0_c_double, 2.0_c_double), COAG_INVALID_ARGUMENT, "removal exponent 2")
    call expect(coag_sim_set_source(sim, 1.0_c_double, 7, 1.0_c_double, 0.0_c_double), COAG_INVALID_ARGUMENT, &
         "source kind 7")
    call ok(coag_sim_advance_to(sim, 2.0_c_double, c_null_ptr))
    b%struct_size = c_sizeof(b)
    call ok(coag_sim_books(sim, b))
    call ok(coag_sim_particle_count(sim, n))
    call ok(coag_sim_moment(sim, 0.0_c_double, m0))
    call ok(coag_sim_moment(sim, 1.0_c_double, m1))
    v = real(n, c_double) / m0
    call check(b%initial_number + b%injected_number - b%removed_number - b%merged == n, "books: the number")
    call check(abs(b%initial_mass + b%injected_mass - b%removed_mass + b%grown_mass - m1 * v) < 1e-9_c_double * m1 * v, &
         "books: the mass")
    call check(b%injected_number > 0 .and. b%removed_number > 0 .and. b%grown_mass > 0, "every process acted")
    call ok(coag_sim_set_source_sizes(sim, 0.5_c_double, [1.0_c_double, 3.0_c_double], 2_c_size_t))
    call ok(coag_sim_set_source_schedule(sim, [3.0_c_double, 4.0_c_double], [0.0_c_double, 1.0_c_double], 2_c_size_t))
    ! host rates: within their bound they run; a bound below the rate is an invalid rate
    call ok(coag_sim_set_removal_callback(sim, c_funloc(size_rate), c_loc(rk), 0.5_c_double, 7_c_int64_t))
    call ok(coag_sim_set_growth_callback(sim, c_funloc(size_rate), c_loc(rk), 0.5_c_double, 8_c_int64_t))
    call ok(coag_sim_advance_to(sim, 2.5_c_double, c_null_ptr))
    call ok(coag_sim_set_removal_callback(sim, c_funloc(size_rate), c_loc(rk), 0.1_c_double, 7_c_int64_t))
    call expect(coag_sim_advance_to(sim, 3.0_c_double, c_null_ptr), COAG_INVALID_RATE, "a host rate above its bound")
    call expect(coag_sim_set_growth_callback(sim, c_funloc(size_rate), c_loc(rk), -1.0_c_double, 8_c_int64_t), &
         COAG_INVALID_ARGUMENT, "a negative bound")
    call expect(coag_sim_set_source_callback(sim, c_funloc(size_rate), c_loc(rk), 0.5_c_double, 9_c_int64_t), &
         COAG_UNSUPPORTED, "a source rate function beside a schedule")
    call ok(coag_sim_set_removal_callback(sim, c_null_funptr, c_null_ptr, 1.0_c_double, 0_c_int64_t))
    call ok(coag_sim_set_growth_callback(sim, c_null_funptr, c_null_ptr, 1.0_c_double, 0_c_int64_t))
    call expect(coag_sim_set_source_schedule(sim, [4.0_c_double, 3.0_c_double], [0.0_c_double, 1.0_c_double], &
         2_c_size_t), COAG_INVALID_ARGUMENT, "a schedule going back in time")
    call expect(coag_sim_set_source_sizes(sim, 0.5_c_double, [1.0_c_double, -3.0_c_double], 2_c_size_t), &
         COAG_INVALID_ARGUMENT, "a listed source with a negative size")
    call ok(coag_sim_clear_processes(sim))
    call expect(coag_sim_books(sim, b), COAG_UNSUPPORTED, "no books without processes")
    ! host classes: the projection keeps number and mass; a population built back has
    ! each class within one particle; rates are the change over the step
    x = [1.0_c_double, 2.0_c_double, 4.0_c_double, 8.0_c_double, 16.0_c_double, 64.0_c_double, 1024.0_c_double]
    call ok(coag_sim_project(sim, x, 7_c_size_t, cn, outside))
    call ok(coag_sim_moment(sim, 0.0_c_double, m0))
    call ok(coag_sim_moment(sim, 1.0_c_double, m1))
    call check(abs(sum(cn) + outside(1) + outside(3) - m0) < 1e-12_c_double * m0, "classes: the number")
    call check(abs(sum(cn * x) + outside(2) + outside(4) - m1) < 1e-12_c_double * m1, "classes: the mass")
    call ok(coag_sim_set_classes(sim, x, cn, 7_c_size_t))
    call ok(coag_sim_project(sim, x, 7_c_size_t, cn2, outside))
    call check(maxval(abs(cn2 - cn)) * v <= 1.0_c_double + 1e-9_c_double, "classes: within one particle")
    call ok(coag_class_rates(cn, cn2, 7_c_size_t, 0.5_c_double, rates))
    call check(abs(rates(1) - (cn2(1) - cn(1)) / 0.5_c_double) < 1e-15_c_double, "classes: rates")
    call expect(coag_class_rates(cn, cn2, 7_c_size_t, 0.0_c_double, rates), COAG_INVALID_ARGUMENT, "rates: dt 0")
    x(3) = x(2)
    call expect(coag_sim_set_classes(sim, x, cn, 7_c_size_t), COAG_INVALID_ARGUMENT, "classes: pivots not ascending")
    call coag_sim_free(sim)
    call coag_kernel_free(k)
  end subroutine test_processes

  ! core's sectional reference: the constant kernel's M0 = 2/(2 + t) from monomers (the
  ! grid reaches far past the sizes present), then a monomer source and dilution
  ! (M1' = S - lambda M1, closed form); refusals
  subroutine test_sectional()
    type(c_ptr) :: k, s
    real(c_double) :: x(64), n(64), m0, m1, t
    integer :: i
    k = kernel("constant", [1.0_c_double])
    do i = 1, 64
      x(i) = real(i, c_double)
    end do
    call ok(coag_sectional_new(k, x, 64_c_size_t, s))
    n = 0.0_c_double
    n(1) = 1.0_c_double
    call ok(coag_sectional_set_numbers(s, n, 64_c_size_t))
    call ok(coag_sectional_advance_to(s, 1.0_c_double, 1e-3_c_double))
    call ok(coag_sectional_moment(s, 0.0_c_double, m0, t))
    call check(abs(m0 - 2.0_c_double / 3.0_c_double) < 1e-10_c_double .and. abs(t - 1.0_c_double) < 1e-15_c_double, "sectional: M0")
    call ok(coag_sectional_moment(s, 1.0_c_double, m1, t))
    call check(abs(m1 - 1.0_c_double) < 1e-12_c_double, "sectional: M1 kept")
    call ok(coag_sectional_set_processes(s, 0.5_c_double, 1.0_c_double, 0.25_c_double, 0.0_c_double, &
         0.0_c_double, 0.0_c_double))
    call ok(coag_sectional_add(s, 1.5_c_double, 0.0_c_double))
    call ok(coag_sectional_advance_to(s, 3.0_c_double, 1e-3_c_double))
    call ok(coag_sectional_moment(s, 1.0_c_double, m1, t))
    call check(abs(m1 - (2.0_c_double - exp(-0.5_c_double))) < 1e-8_c_double, "sectional: M1 with a source and dilution")
    call ok(coag_sectional_numbers(s, n, 64_c_size_t))
    call check(abs(sum(n * x) - m1) < 1e-12_c_double, "sectional: numbers")
    call expect(coag_sectional_numbers(s, n, 63_c_size_t), COAG_BUFFER_TOO_SMALL, "sectional: numbers' length")
    call expect(coag_sectional_advance_to(s, 1.0_c_double, 1e-3_c_double), COAG_TIME_BACKWARDS, "sectional: backwards")
    x(3) = x(2)
    call coag_sectional_free(s)
    call expect(coag_sectional_new(k, x, 64_c_size_t, s), COAG_INVALID_ARGUMENT, "sectional: pivots not ascending")
    call coag_kernel_free(k)
  end subroutine test_sectional

  subroutine test_gas()
    character(len=10), parameter :: names(4) = [character(len=10) :: "momentum-x", "momentum-y", "momentum-z", "energy"]
    type(c_ptr) :: hs, o, ds, db
    real(c_double) :: before(4), after(4), vel(6)
    integer(c_int64_t) :: n
    integer(c_int64_t), allocatable :: dsz(:)
    real(c_double), allocatable :: dvel(:)
    integer(c_int8_t), allocatable :: ck(:)
    integer :: i
    hs = kernel("hard-spheres", [1.0_c_double])
    o = seeded(6, 0)
    call ok(coag_sim_new_maxwellian(cs("dsmc"), hs, o, [300_c_int64_t, 100_c_int64_t], [1.0_c_double, 2.0_c_double], &
         2_c_size_t, 4000.0_c_double, ds))
    call coag_options_free(o)
    do i = 1, 4
       call ok(coag_sim_observable(ds, cs(trim(names(i))), before(i)))
    end do
    call ok(coag_sim_advance_to(ds, 20.0_c_double, c_null_ptr))
    do i = 1, 4
       call ok(coag_sim_observable(ds, cs(trim(names(i))), after(i)))
    end do
    call check(maxval(abs(after(1:3) - before(1:3))) < 1e-9_c_double .and. &
         abs(after(4) - before(4)) < 1e-12_c_double * before(4), "dsmc conservation")
    call ok(coag_sim_particle_count(ds, n))
    allocate(dsz(n), dvel(3 * n))
    call ok(coag_sim_velocities(ds, dsz, dvel, int(n, c_size_t)))
    call check(sum(dsz) == 500 .and. n == 400, "dsmc particles")
    call expect(coag_sim_velocities(ds, dsz, dvel, int(n - 1, c_size_t)), COAG_BUFFER_TOO_SMALL, "short buffers")
    ck = snapshot(ds)
    call ok(coag_sim_advance_to(ds, 30.0_c_double, c_null_ptr))
    vel = [1.0_c_double, 0.0_c_double, 0.0_c_double, -1.0_c_double, 0.5_c_double, 0.0_c_double]
    call ok(coag_sim_new_velocities(cs("dsmc"), hs, c_null_ptr, [1_c_int64_t, 2_c_int64_t], vel, 2_c_size_t, &
         10.0_c_double, db))
    call ok(coag_sim_velocities(db, dsz, dvel, int(n, c_size_t)))
    call check(all(dsz(1:2) == [1, 2]) .and. all(same(dvel(1:6), vel)), "particles read back as given")
    call expect(coag_sim_restore(db, ck(1:size(ck) - 1), size(ck, kind=c_size_t) - 1), COAG_BAD_CHECKPOINT, "truncated")
    call ok(coag_sim_restore(db, ck, size(ck, kind=c_size_t)))
    call ok(coag_sim_advance_to(db, 30.0_c_double, c_null_ptr))
    call check(sim_is(db, snapshot(ds)), "dsmc checkpoint continues bit for bit")
    call coag_sim_free(db)
    call coag_sim_free(ds)
    call coag_kernel_free(hs)
  end subroutine test_gas

  ! Langevin batches: b = 0 outside the unit ball keeps E|U|^2 = |u0|^2 + 3 T; a Fortran
  ! friction drift in caller memory; clone, checkpoint, bounded calls; first hits
  subroutine test_langevin()
    type(coag_langevin_config) :: lgc
    type(coag_first_hits) :: fh
    type(c_ptr) :: lb, lc, lw
    real(c_double), target :: lt, radius, rate, mean, se, mx
    integer(c_size_t), target :: ldim, lnw
    integer(c_int64_t), target :: ln, absorbed, hits
    integer(c_int32_t), target :: polls(2)
    real(c_double), allocatable, target :: lxs(:), lfirst(:), lws(:), x2(:)
    integer(c_int64_t), allocatable, target :: lhits(:)
    integer(c_int8_t), allocatable :: lck(:)
    integer(c_size_t) :: lnck, lwb
    call ok(coag_langevin_default_config(lgc, c_sizeof(lgc)))
    call check(lgc%dim == 1 .and. same(lgc%dt, 0.01_c_double) .and. same(lgc%sigma, 1.0_c_double) .and. &
         lgc%drift == COAG_DRIFT_ZERO .and. lgc%struct_size == 96 .and. c_sizeof(fh) == 136, "defaults, sizes")
    lgc%dim = 3
    lgc%radius = 1
    lgc%dt = 0.02_c_double
    call ok(coag_langevin_new(lgc, 20000_c_int64_t, [1.2_c_double, 0.0_c_double, 0.0_c_double], &
         [-2.0_c_double, 0.0_c_double, 0.0_c_double], 11_c_int64_t, 0_c_int64_t, lb))
    call ok(coag_langevin_advance_to(lb, 1.0_c_double, c_null_ptr))
    radius = 1
    call ok(coag_langevin_mean(lb, c_funloc(u_squared), c_loc(radius), mean, se, c_loc(absorbed)))
    call check(abs(mean - 7) < zl * se .and. absorbed == 0, "langevin E|U|^2 = |u0|^2 + 3T")
    call ok(coag_langevin_info(lb, c_loc(lt), c_loc(ldim), c_loc(ln)))
    call check(same(lt, 1.0_c_double) .and. ldim == 3 .and. ln == 20000, "langevin info")
    allocate(lxs(3 * 20000), lhits(20000), lfirst(20000))
    call ok(coag_langevin_state(lb, c_loc(lxs), c_null_ptr, c_loc(lhits), c_loc(lfirst), 20000_c_size_t))
    call check(all(lxs(1::3)**2 + lxs(2::3)**2 + lxs(3::3)**2 >= 1 - 1e-12_c_double), "positions outside the ball")
    call ok(coag_langevin_mean(lb, c_null_funptr, c_null_ptr, mean, se, c_null_ptr))
    call check(sum(lhits) > 1000 .and. minval(lfirst) > 0 .and. abs(mean - sum(lhits) / 20000.0_c_double) < 1e-12, &
         "langevin hits")
    ! a checkpoint and a clone continue bit for bit; refusals change nothing
    call ok(coag_langevin_checkpoint_size(lb, lnck))
    allocate(lck(lnck))
    call ok(coag_langevin_save(lb, lck, lnck, c_loc(lnw)))
    call ok(coag_langevin_clone(lb, lc))
    call ok(coag_langevin_advance_to(lb, 2.0_c_double, c_null_ptr))
    call ok(coag_langevin_advance_to(lc, 2.0_c_double, c_null_ptr))
    allocate(x2(3 * 20000))
    call ok(coag_langevin_state(lb, c_loc(lxs), c_null_ptr, c_null_ptr, c_null_ptr, 20000_c_size_t))
    call ok(coag_langevin_state(lc, c_loc(x2), c_null_ptr, c_null_ptr, c_null_ptr, 20000_c_size_t))
    call check(all(same(lxs, x2)), "langevin clone continues bit for bit")
    call ok(coag_langevin_restore(lc, lck, lnw))
    call ok(coag_langevin_info(lc, c_loc(lt), c_null_ptr, c_null_ptr))
    call check(same(lt, 1.0_c_double), "langevin restore")
    call ok(coag_langevin_advance_to(lc, 2.0_c_double, c_null_ptr))
    call ok(coag_langevin_state(lc, c_loc(x2), c_null_ptr, c_null_ptr, c_null_ptr, 20000_c_size_t))
    call check(all(same(lxs, x2)), "langevin restored run continues bit for bit")
    call expect(coag_langevin_advance_to(lc, 0.5_c_double, c_null_ptr), COAG_TIME_BACKWARDS, "langevin time backwards")
    call expect(coag_langevin_restore(lc, lck(1:10), 10_c_size_t), COAG_BAD_CHECKPOINT, "a truncated checkpoint")
    call expect(coag_langevin_state(lc, c_loc(x2), c_null_ptr, c_null_ptr, c_null_ptr, 19999_c_size_t), &
         COAG_BUFFER_TOO_SMALL, "a short state buffer")
    call ok(coag_langevin_state(lc, c_loc(x2), c_null_ptr, c_null_ptr, c_null_ptr, 20000_c_size_t))
    call check(all(same(lxs, x2)), "refusals changed the batch")
    call coag_langevin_free(lc)
    call coag_langevin_free(lb)
    ! a Fortran friction drift far from the wall, in caller memory: the scheme's own mean
    ! x_T (x' = x + h u, u' = (1 - g h) u + noise), no hits; bounded calls
    call ok(coag_langevin_default_config(lgc, c_sizeof(lgc)))
    rate = 0.7_c_double
    lgc%dt = 0.05_c_double
    lgc%drift = COAG_DRIFT_CALLBACK
    lgc%drift_fn = c_funloc(friction_drift)
    lgc%drift_user_data = c_loc(rate)
    call ok(coag_langevin_workspace_size(lgc, 4000_c_int64_t, lwb))
    allocate(lws(lwb / 8))
    call ok(coag_langevin_new_in(lgc, 4000_c_int64_t, [1e6_c_double], [0.5_c_double], 5_c_int64_t, 0_c_int64_t, &
         c_loc(lws), lwb, lw))
    call ok(coag_langevin_new(lgc, 4000_c_int64_t, [1e6_c_double], [0.5_c_double], 5_c_int64_t, 0_c_int64_t, lb))
    call ok(coag_langevin_set_work_limit(lw, 4000_c_int64_t * 7))
    polls = 0
    do while (coag_langevin_advance_to(lw, 2.0_c_double, c_null_ptr) == COAG_INTERRUPTED)
       polls(1) = polls(1) + 1
    end do
    call ok(coag_langevin_info(lw, c_loc(lt), c_null_ptr, c_null_ptr))
    call check(polls(1) >= 5 .and. same(lt, 2.0_c_double), "work limit: stopped and continued")
    call ok(coag_langevin_set_work_limit(lw, 0_c_int64_t))
    call ok(coag_langevin_advance_to(lb, 2.0_c_double, c_null_ptr))
    call expect(coag_langevin_save(lb, lck, 0_c_size_t, c_null_ptr), COAG_BUFFER_TOO_SMALL, "a short checkpoint buffer")
    mx = 0.5_c_double * (1 - (1 - rate * lgc%dt)**40) / rate   ! sum of h u_k, u_k = 0.5 (1 - g h)^k, k < 40
    call ok(coag_langevin_state(lb, c_loc(x2), c_null_ptr, c_null_ptr, c_null_ptr, 4000_c_size_t))
    mean = sum(x2(1:4000) - 1e6_c_double) / 4000
    se = sqrt(sum((x2(1:4000) - 1e6_c_double - mean)**2) / 3999 / 4000)
    call check(abs(mean - mx) < zl * se, "friction drift: the scheme's mean position")
    call ok(coag_langevin_state(lw, c_loc(lxs), c_null_ptr, c_null_ptr, c_null_ptr, 4000_c_size_t))
    call check(all(same(lxs(1:4000), x2(1:4000))), "caller memory and the library's: the same run")
    call ok(coag_langevin_mean(lw, c_null_funptr, c_null_ptr, mean, se, c_null_ptr))
    call check(abs(mean) < tiny(mean), "no hits far from the wall")
    polls = [0, 1]
    call ok(coag_langevin_set_cancel_callback(lw, c_funloc(cancel_at), c_loc(polls)))
    call expect(coag_langevin_advance_to(lw, 1000.0_c_double, c_null_ptr), COAG_INTERRUPTED, "cancelled")
    call ok(coag_langevin_info(lw, c_loc(lt), c_null_ptr, c_null_ptr))
    call check(polls(1) == 1 .and. lt > 2 .and. lt < 1000, "cancelled at the first poll")
    call ok(coag_langevin_set_cancel_callback(lw, c_null_funptr, c_null_ptr))
    call coag_langevin_free(lb)
    call coag_langevin_free(lw)
    ! the free-flight kernel from first hits: pi R^2 <|v|> = pi R^2 sqrt(8/pi)
    fh = coag_first_hits(c_sizeof(fh), 3, 0.5_c_double, 10.0_c_double, 0.4_c_double, 1.0_c_double, 0.1_c_double, &
         0.0_c_double, 1.0_c_double, 100000_c_int64_t, COAG_DRIFT_ZERO, 0.0_c_double, c_null_funptr, c_null_ptr, &
         0_c_int64_t, c_null_funptr, c_null_ptr)
    call ok(coag_first_hit_kernel(fh, 7_c_int64_t, 0_c_int64_t, mean, se, c_loc(hits)))
    radius = acos(-1.0_c_double) * 0.25_c_double * sqrt(8 / acos(-1.0_c_double))
    call check(abs(mean - radius) < zl * se .and. hits > 100, "free-flight kernel")
    fh%outer = 0.4_c_double
    call expect(coag_first_hit_kernel(fh, 7_c_int64_t, 0_c_int64_t, mean, se, c_null_ptr), COAG_INVALID_ARGUMENT, &
         "outer radius below R")
  end subroutine test_langevin

end program test_fortran
