//! The mass-flow scheme's checkpoints: the point source, sorting, M1, Δt, the clock,
//! the step count, the totals and the sizes.

use super::{MassFlow, Sorting, check_setup, split};
use crate::error::{Error, Result};
use crate::kernel::{CoagulationKernel, FragmentationKernel};
use crate::scheme::StepReport;

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>
    crate::checkpoint::Checkpoint for MassFlow<K, F, B>
{
    fn save(&self, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::header;
        use crate::scheme::tag;
        header(w, tag::MASSFLOW);
        w.u64(self.points.fingerprint());
        w.u64(match self.sorting {
            Sorting::Adaptive => 0,
            Sorting::Full => 1,
        });
        w.f64(self.mass);
        w.f64(self.dt);
        w.f64(self.time);
        w.u64(self.steps);
        self.totals.save(w);
        w.f64s(self.sizes());
    }

    fn restore(&mut self, r: &mut crate::checkpoint::Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        use crate::scheme::tag;
        check_header(r, tag::MASSFLOW)?;
        if r.u64()? != self.points.fingerprint() {
            return Err(Error::Checkpoint {
                what: "the point source (or its randomisation) differs",
            });
        }
        let sorting = match r.u64()? {
            0 => Sorting::Adaptive,
            1 => Sorting::Full,
            _ => {
                return Err(Error::Checkpoint {
                    what: "unknown sorting",
                });
            }
        };
        let (mass, dt, time, steps) = (r.f64()?, r.f64()?, r.f64()?, r.u64()?);
        let totals = StepReport::read(r)?;
        // read into the next-sizes half (scratch until a step), so that a refused
        // checkpoint leaves the sizes as they were and nothing is allocated
        let (_, next, ..) = split(self.ws.as_mut(), self.n, self.cur);
        r.f64s_into(next).map_err(|_| Error::Checkpoint {
            what: "different number of particles",
        })?;
        // the constructor's checks, the sizes' order (the adaptive sort merges into
        // it), a time that is finite and not negative, a step count whose point index
        // fits the sequence, and nothing after the state
        let n = next.len() as u64;
        if check_setup(next, mass, dt).is_err()
            || next.windows(2).any(|w| w[0] > w[1])
            || !(time >= 0.0 && time.is_finite())
            || steps
                .checked_add(1)
                .and_then(|s| s.checked_mul(n))
                .is_none()
        {
            return Err(Error::Checkpoint {
                what: "invalid values (sizes not positive, finite and ascending, or mass, dt, time or step count out of range)",
            });
        }
        r.finish()?;
        self.sorting = sorting;
        self.mass = mass;
        self.dt = dt;
        self.time = time;
        self.steps = steps;
        self.totals = totals;
        self.cur ^= 1;
        Ok(())
    }
}
