! The bind(c) callbacks tests/fortran/test_fortran.f90 passes to libcoagula (user
! kernels, fragmentation, random streams, cancellation, drifts): compile it first.

module test_callbacks
  use, intrinsic :: iso_c_binding
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
  use coagula
  implicit none
  integer(c_int32_t) :: reentry_status = COAG_OK   ! what a sim said to its own callback
contains
  ! a removal (or growth) rate per particle: k (user_data) below size 10, k/2 above
  real(c_double) function size_rate(x, ud) bind(c)
    real(c_double), value :: x
    type(c_ptr), value :: ud
    real(c_double), pointer :: k
    call c_f_pointer(ud, k)
    size_rate = k
    if (x > 10) size_rate = k / 2
  end function
  ! K = k (user_data), sizes checked positive (else an invalid rate)
  real(c_double) function user_rate(x, y, ud) bind(c)
    real(c_double), value :: x, y
    type(c_ptr), value :: ud
    real(c_double), pointer :: k
    call c_f_pointer(ud, k)
    user_rate = k
    if (.not. (x > 0 .and. y > 0)) user_rate = -1
  end function
  real(c_double) function user_sup(lo, hi, ud) bind(c)
    real(c_double), value :: lo, hi
    type(c_ptr), value :: ud
    real(c_double), pointer :: k
    call c_f_pointer(ud, k)
    user_sup = abs(k)
    if (lo > hi) user_sup = -1
  end function
  real(c_double) function user_block_sup(x0, x1, y0, y1, ud) bind(c)
    real(c_double), value :: x0, x1, y0, y1
    type(c_ptr), value :: ud
    real(c_double), pointer :: k
    call c_f_pointer(ud, k)
    user_block_sup = abs(k)
    if (x0 > x1 .or. y0 > y1) user_block_sup = -1
  end function
  subroutine user_factors(x, a, b, ud) bind(c)
    real(c_double), value :: x
    real(c_double), intent(out) :: a(*), b(*)
    type(c_ptr), value :: ud
    real(c_double), pointer :: k
    call c_f_pointer(ud, k)
    a(1) = 0.5_c_double * abs(k)
    b(1) = 1
    if (.not. x > 0) a(1) = -1
  end subroutine
  ! binary uniform break-up at rate d(1) (user_data d(2): the pieces drawn, counted):
  ! the size-biased piece has F(y) = (y/x)^2
  real(c_double) function frag_rate(x, ud) bind(c)
    real(c_double), value :: x
    type(c_ptr), value :: ud
    real(c_double), pointer :: d(:)
    call c_f_pointer(ud, d, [2])
    frag_rate = d(1)
    if (.not. x > 0) frag_rate = -1
  end function
  real(c_double) function frag_piece(x, u, ud) bind(c)
    real(c_double), value :: x, u
    type(c_ptr), value :: ud
    real(c_double), pointer :: d(:)
    call c_f_pointer(ud, d, [2])
    d(2) = d(2) + 1
    frag_piece = x * sqrt(u)
  end function
  ! counts its polls (p(1)) and cancels at poll p(2)
  integer(c_int32_t) function cancel_at(ud) bind(c)
    type(c_ptr), value :: ud
    integer(c_int32_t), pointer :: p(:)
    call c_f_pointer(ud, p, [2])
    p(1) = p(1) + 1
    cancel_at = merge(1, 0, p(1) >= p(2))
  end function
  ! a cancellation callback that calls back into its own sim (user_data)
  integer(c_int32_t) function call_back_in(ud) bind(c)
    type(c_ptr), value :: ud
    if (reentry_status == COAG_OK) reentry_status = coag_sim_set_dt(ud, 0.5_c_double)
    call_back_in = 0
  end function
  ! xorshift64 on the state in user_data
  integer(c_int64_t) function rng_next(ud) bind(c)
    type(c_ptr), value :: ud
    integer(c_int64_t), pointer :: s
    call c_f_pointer(ud, s)
    s = ieor(s, ishft(s, 13))
    s = ieor(s, ishft(s, -7))
    s = ieor(s, ishft(s, 17))
    rng_next = s
  end function
  ! a stuck stream: the same word every call (calls counted)
  integer(c_int64_t) function rng_stuck(ud) bind(c)
    type(c_ptr), value :: ud
    integer(c_int64_t), pointer :: calls
    call c_f_pointer(ud, calls)
    calls = calls + 1
    rng_stuck = 42
  end function
  ! |u|^2 of a trajectory outside the ball of radius user_data (NaN inside: a wall bug)
  real(c_double) function u_squared(x, u, dim, ud) bind(c)
    real(c_double), intent(in) :: x(*), u(*)
    integer(c_size_t), value :: dim
    type(c_ptr), value :: ud
    real(c_double), pointer :: radius
    call c_f_pointer(ud, radius)
    u_squared = sum(u(1:dim)**2)
    if (sum(x(1:dim)**2) < radius**2 - 1e-12_c_double) u_squared = ieee_value(u_squared, ieee_quiet_nan)
  end function
  ! friction b = -rate u (rate in user_data); a negative time or NaN position fails
  integer(c_int32_t) function friction_drift(t, x, u, dim, out, ud) bind(c)
    real(c_double), value :: t
    real(c_double), intent(in) :: x(*), u(*)
    integer(c_size_t), value :: dim
    real(c_double), intent(out) :: out(*)
    type(c_ptr), value :: ud
    real(c_double), pointer :: rate
    call c_f_pointer(ud, rate)
    out(1:dim) = -rate * u(1:dim)
    friction_drift = merge(1, 0, t < 0 .or. any(ieee_is_nan(x(1:dim))))
  end function
end module test_callbacks
