//! One frame's samples split over several devices. The work is the frame's region for its
//! range of sample indices, cut into units of (band of rows, run of samples) that the
//! devices take as they finish, each device on its own thread: a faster device simply takes
//! more. A unit's size follows guided self-scheduling, about half of the device's share of
//! what is left, so units shrink towards the end and the devices finish together. A device
//! takes a unit only if it would finish it before the others, at their measured speed,
//! would finish everything left: a much slower device never holds up the frame, it is
//! dropped from the tail. A device under [`MIN_SHARE`] of the speed together stops after
//! its first unit.
//!
//! The sums are fixed-point integers ([`crate::render::integrator::to_fixed`]) and each
//! sample's random numbers depend only on (seed, pixel, sample), so the image does not
//! depend on which device took which unit: on devices of one implementation it equals the
//! one-device render bit for bit.

use std::ops::Range;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use super::Renderer;
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::render::integrator::{Accumulation, Region, SampleSettings};
use crate::report::Progress;

/// Sums of at most 65,536 samples of at most 2^42 each fit (`to_fixed`).
const OVERFLOW: &str = "a frame's sums fit 63 bits";
/// The longest a unit is meant to take, so that speeds are re-measured and a stop is seen.
const MAX_UNIT_SECONDS: f64 = 2.0;
/// A device slower than this share of all the devices' speed together stops after its
/// first unit: it would cost the others more than it adds. Measured: a 16-core PoCL device
/// beside an H200 took 2.3% of a frame's samples and made the H200's own kernels 6% slower.
const MIN_SHARE: f64 = 0.05;
/// Bands of rows the region is cut into at least: a device's first unit, one sample of a
/// band, measures its speed without holding up the frame much. Not more: a GPU waits for
/// each launch, and a launch over a small band is short enough for the host's latency
/// (worse with a busy CPU device beside it) to cost (measured: 16 bands cost an H200 14%
/// beside a 16-core PoCL device).
const MIN_BANDS: u64 = 4;

/// What one device did for the frame.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct DeviceShare {
    /// The device's name.
    pub device: String,
    /// Pixel samples it took (a pixel's sample counts once).
    pub pixel_samples: u64,
    /// The share of the frame's pixel samples, 0 to 1.
    pub share: f64,
    /// Units it rendered.
    pub units: u32,
    /// Wall time it spent rendering its units, ms (its busy time).
    pub busy_ms: f64,
    /// Its kernels' device time, ms.
    pub kernel_ms: f64,
    /// Whether it stopped before the work ran out, because it would have finished its next
    /// unit after the other devices finished everything.
    pub dropped_from_tail: bool,
}

/// A band of rows and the next sample index no device has taken yet.
struct Band {
    region: Region,
    next: u32,
}

/// The work left and what is known of each device's speed.
struct Queue {
    bands: Vec<Band>,
    end: u32,
    /// Pixel samples per second, once a device has finished a unit.
    rates: Vec<Option<f64>>,
    /// When each device's unit in flight is expected to end, and its pixel samples.
    in_flight: Vec<Option<(Instant, u64)>>,
    /// Devices that have stopped taking work: the others no longer count on them.
    gone: Vec<bool>,
}

impl Queue {
    fn left(&self) -> u64 {
        self.bands
            .iter()
            .map(|b| (self.end - b.next) as u64 * b.region.pixels() as u64)
            .sum()
    }

    /// The next unit for device `d`: a band and its samples; `None` when the work is gone
    /// or when the other devices would finish it all before `d` finished a unit.
    fn take(&mut self, d: usize, now: Instant) -> Option<(usize, Range<u32>)> {
        let b = (0..self.bands.len()).max_by_key(|&b| self.end - self.bands[b].next)?;
        let band = &self.bands[b];
        let left_in_band = self.end - band.next;
        if left_in_band == 0 {
            return None;
        }
        let pixels = band.region.pixels() as f64;
        let samples = match self.rates[d] {
            // Not measured yet: one sample of the band measures it.
            None => 1,
            Some(rate) => {
                let left = self.left() as f64;
                let others: f64 = (0..self.rates.len())
                    .filter(|&o| o != d && !self.gone[o])
                    .filter_map(|o| self.rates[o])
                    .sum();
                // What the others still have in flight, as pixel samples.
                let in_flight: f64 = (0..self.rates.len())
                    .filter(|&o| o != d && !self.gone[o])
                    .filter_map(|o| Some((self.in_flight[o]?, self.rates[o]?)))
                    .map(|((end, _), rate)| end.saturating_duration_since(now).as_secs_f64() * rate)
                    .sum();
                let total = rate + others;
                if rate < MIN_SHARE * total {
                    return None;
                }
                let guided = rate * (left / total) / 2.0;
                let mut n = (guided.min(rate * MAX_UNIT_SECONDS) / pixels)
                    .floor()
                    .max(1.0);
                if others > 0.0 {
                    // Finish the unit before the others would finish everything left.
                    let limit = (rate * (left + in_flight) / others / pixels).floor();
                    if limit < 1.0 {
                        return None;
                    }
                    n = n.min(limit);
                }
                (n as u32).min(left_in_band)
            }
        };
        let band = &mut self.bands[b];
        let first = band.next;
        band.next += samples;
        Some((b, first..first + samples))
    }
}

/// Adds samples `samples` of every pixel of `accumulation`'s region to it, split over
/// `renderers` (one per device, all prepared for the same scene). Returns what each
/// device did. `stop`, once set, ends the work at the next launch of each device.
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_samples(
    renderers: &mut [Renderer],
    names: &[String],
    camera: &Camera,
    settings: &SampleSettings,
    samples: Range<u32>,
    accumulation: &mut Accumulation,
    stop: &AtomicBool,
    progress: bool,
) -> Result<Vec<DeviceShare>> {
    let region = accumulation.region;
    let (width, height) = accumulation.image_size();
    let spp = samples.len() as u64;
    // Enough units for every device to get several, even at a few samples per pixel.
    let wanted = (8 * renderers.len() as u64)
        .div_ceil(spp.max(1))
        .max(MIN_BANDS);
    let bands = wanted.clamp(1, region.height() as u64) as u32;
    let queue = Mutex::new(Queue {
        bands: (0..bands)
            .map(|i| Band {
                region: Region {
                    y0: region.y0 + region.height() * i / bands,
                    y1: region.y0 + region.height() * (i + 1) / bands,
                    ..region
                },
                next: samples.start,
            })
            .collect(),
        end: samples.end,
        rates: vec![None; renderers.len()],
        in_flight: vec![None; renderers.len()],
        gone: vec![false; renderers.len()],
    });
    let total = spp * region.pixels() as u64;
    let bar = Progress::new(
        progress,
        format!("sampling on {} devices", renderers.len()),
        spp,
        "samples",
    );
    // Pixel samples done (for the bar) and the frame's sums.
    let done = Mutex::new((0u64, &mut *accumulation));
    let failed = AtomicBool::new(false);
    let shares: Vec<Result<DeviceShare>> = std::thread::scope(|s| {
        let handles: Vec<_> = renderers
            .iter_mut()
            .enumerate()
            .map(|(d, renderer)| {
                let (queue, done, bar, failed) = (&queue, &done, &bar, &failed);
                s.spawn(move || {
                    let mut share = DeviceShare {
                        device: names[d].clone(),
                        ..DeviceShare::default()
                    };
                    let stopped = || stop.load(Ordering::Relaxed) || failed.load(Ordering::Relaxed);
                    // PoCL compiles a kernel at its first launch, once for a launch from the
                    // origin and once for one from elsewhere: two one-pixel launches do it
                    // before the first unit, which would otherwise measure the compiler.
                    for at in [0, 1] {
                        let (x, y) = (
                            region.x0 + at.min(region.width() - 1),
                            region.y0 + at.min(region.height() - 1),
                        );
                        let pixel = Region {
                            x0: x,
                            y0: y,
                            x1: x + 1,
                            y1: y + 1,
                        };
                        let mut warm = Accumulation::of_region(width, height, pixel);
                        renderer
                            .render_samples(
                                camera,
                                settings,
                                samples.start..samples.start + 1,
                                &mut warm,
                                stop,
                                false,
                            )
                            .inspect_err(|_| failed.store(true, Ordering::Relaxed))?;
                    }
                    let mut session = renderer
                        .begin_samples(camera, settings, region)
                        .inspect_err(|_| failed.store(true, Ordering::Relaxed))?;
                    loop {
                        if stopped() {
                            break;
                        }
                        let now = Instant::now();
                        let unit = {
                            let mut q = queue.lock().expect("no thread panics holding it");
                            let unit = q.take(d, now);
                            if unit.is_none() {
                                q.gone[d] = true;
                                share.dropped_from_tail = q.left() > 0;
                            }
                            if let (Some((b, s)), Some(rate)) = (&unit, q.rates[d]) {
                                let work = s.len() as u64 * q.bands[*b].region.pixels() as u64;
                                let secs = work as f64 / rate;
                                q.in_flight[d] =
                                    Some((now + std::time::Duration::from_secs_f64(secs), work));
                            }
                            unit.map(|(b, s)| (q.bands[b].region, s))
                        };
                        let Some((band, range)) = unit else { break };
                        let began = Instant::now();
                        let work = range.len() as u64 * band.pixels() as u64;
                        let kernel_ms = match session.as_mut() {
                            // The sums stay on the device: the unit is its launches alone.
                            Some(session) => renderer
                                .add_samples(session, band.y0..band.y1, range, stop)
                                .inspect_err(|_| failed.store(true, Ordering::Relaxed))?,
                            None => {
                                let mut part = Accumulation::of_region(width, height, band);
                                let times = renderer
                                    .render_samples(camera, settings, range, &mut part, stop, false)
                                    .inspect_err(|_| failed.store(true, Ordering::Relaxed))?;
                                let mut done = done.lock().expect("no thread panics holding it");
                                done.1.add(&part).expect(OVERFLOW);
                                times.trace_ms
                            }
                        };
                        let secs = began.elapsed().as_secs_f64();
                        share.pixel_samples += work;
                        share.units += 1;
                        share.busy_ms += secs * 1e3;
                        share.kernel_ms += kernel_ms;
                        {
                            let mut q = queue.lock().expect("no thread panics holding it");
                            // The speed over everything done so far: later units are larger.
                            q.rates[d] =
                                Some(share.pixel_samples as f64 / (share.busy_ms / 1e3).max(1e-6));
                            q.in_flight[d] = None;
                        }
                        let mut done = done.lock().expect("no thread panics holding it");
                        done.0 += work;
                        bar.set_position(done.0 / region.pixels() as u64);
                    }
                    if let Some(session) = session {
                        let began = Instant::now();
                        let sums = renderer
                            .finish_samples(session)
                            .inspect_err(|_| failed.store(true, Ordering::Relaxed))?;
                        share.busy_ms += began.elapsed().as_secs_f64() * 1e3;
                        // Stopped early, a unit holds fewer samples than it was given.
                        share.pixel_samples = sums.pixels.iter().map(|p| p[3] as u64).sum();
                        let mut done = done.lock().expect("no thread panics holding it");
                        done.1.add(&sums).expect(OVERFLOW);
                    }
                    Ok(share)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a device thread does not panic"))
            .collect()
    });
    bar.finish();
    let mut out = Vec::new();
    for share in shares {
        out.push(share?);
    }
    for share in &mut out {
        share.share = share.pixel_samples as f64 / total.max(1) as f64;
        if share.pixel_samples == 0 && !stop.load(Ordering::Relaxed) {
            share.dropped_from_tail = true;
        }
    }
    if out.iter().all(|s| s.pixel_samples == 0) && !stop.load(Ordering::Relaxed) {
        return Err(Error::Invalid(
            "no device took any of the frame's samples".into(),
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn queue(devices: usize, height: u32, samples: Range<u32>) -> Queue {
        Queue {
            bands: vec![Band {
                region: Region::whole(100, height),
                next: samples.start,
            }],
            end: samples.end,
            rates: vec![None; devices],
            in_flight: vec![None; devices],
            gone: vec![false; devices],
        }
    }

    #[test]
    fn an_unmeasured_device_takes_one_sample() {
        let mut q = queue(2, 10, 0..64);
        assert_eq!(q.take(0, Instant::now()), Some((0, 0..1)));
        assert_eq!(q.take(1, Instant::now()), Some((0, 1..2)));
        assert_eq!(q.left(), 62 * 1000);
    }

    #[test]
    fn a_faster_device_takes_larger_units_and_they_shrink() {
        let mut q = queue(2, 10, 0..1000);
        q.bands[0].next = 2;
        // 1000 pixels a band: device 0 does 10 samples a second, device 1 one.
        q.rates = vec![Some(10_000.0), Some(1_000.0)];
        let now = Instant::now();
        let (_, fast) = q.take(0, now).unwrap();
        let (_, slow) = q.take(1, now).unwrap();
        assert!(fast.len() > 5 * slow.len(), "{fast:?} vs {slow:?}");
        let (_, later) = q.take(0, now).unwrap();
        assert!(later.len() <= fast.len(), "{later:?} after {fast:?}");
    }

    #[test]
    fn a_much_slower_device_is_dropped_from_the_tail() {
        let mut q = queue(2, 10, 0..4);
        q.bands[0].next = 2;
        // Two samples left: the fast device does them in 0.2 s, the slow one one in 100 s.
        q.rates = vec![Some(10_000.0), Some(10.0)];
        assert_eq!(q.take(1, Instant::now()), None);
        assert!(q.take(0, Instant::now()).is_some());
    }

    #[test]
    fn a_device_of_a_small_share_stops_after_its_first_unit() {
        let mut q = queue(2, 10, 0..1000);
        q.bands[0].next = 2;
        // 3% of the speed together: plenty of work left, but it stops.
        q.rates = vec![Some(97_000.0), Some(3_000.0)];
        assert_eq!(q.take(1, Instant::now()), None);
        assert!(q.take(0, Instant::now()).is_some());
        q.rates = vec![Some(90_000.0), Some(10_000.0)];
        assert!(q.take(1, Instant::now()).is_some(), "10% keeps working");
    }

    /// Regression: two devices of about the same speed near the end each left the rest to
    /// the other, which had already stopped, and the frame missed 4% of its samples (seen
    /// with PoCL beside Intel's runtime on 2 cores).
    #[test]
    fn a_device_that_stopped_is_not_counted_on() {
        let mut q = queue(2, 10, 0..1000);
        q.bands[0].next = 999;
        q.rates = vec![Some(900.0), Some(1000.0)];
        // Device 0 would finish the last sample after device 1: it leaves it...
        assert_eq!(q.take(0, Instant::now()), None);
        q.gone[0] = true;
        // ... and device 1 must take it, though device 0 is faster on paper now.
        q.rates[0] = Some(5000.0);
        assert!(q.take(1, Instant::now()).is_some());
    }

    #[test]
    fn the_queue_hands_out_every_sample_once() {
        let mut q = queue(3, 10, 5..300);
        q.rates = vec![Some(5000.0), Some(3000.0), Some(100.0)];
        let mut taken = Vec::new();
        let mut d = 0;
        let mut idle = 0;
        while q.left() > 0 && idle < 3 {
            match q.take(d, Instant::now()) {
                Some((_, s)) => {
                    taken.push(s);
                    idle = 0;
                }
                None => idle += 1,
            }
            d = (d + 1) % 3;
        }
        taken.sort_by_key(|s| s.start);
        let mut next = 5;
        for s in taken {
            assert_eq!(s.start, next);
            next = s.end;
        }
        assert_eq!(next, 300);
    }
}
