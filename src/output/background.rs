//! Observers on a thread of their own: the run loop hands each call over a bounded channel
//! and goes on stepping, while the thread makes the samples (the references beside each
//! step: [`SampleInputs::sample`]), formats and writes. Each observer still sees every call,
//! in the run's order, so the files are the same bytes; the main job's references, numbers
//! to text and compressed log then cost the run loop only the copy of a step.

use std::sync::Arc;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::{Scope, ScopedJoinHandle};

use crate::run::frame::{Event, Frame};
use crate::run::{Observer, RunReport, Sample, SampleInputs};
use crate::scene::Scene;
use crate::theory::References;

/// Calls handed over at once: one wake-up of the thread per batch, not per sample.
const BATCH: usize = 64;
/// Batches waiting for the thread at most: a bound on the memory a slow disk can take.
const QUEUE: usize = 16;

/// One call of [`Observer`].
enum Call {
    Init(Box<Scene>),
    References(Arc<References>),
    Step(Box<SampleInputs>),
    Sample(Box<Sample>),
    Frame(Box<Frame>),
    Event(Box<Event>),
    Final(Box<RunReport>),
}

/// An [`Observer`] whose calls are made on a scoped thread, to `observers` in their order.
/// The first error ends the thread; it is returned by the next call, at the latest by
/// [`Observer::observe_final`], which waits for the thread to finish its files.
pub struct Background<'scope> {
    calls: Option<SyncSender<Vec<Call>>>,
    batch: Vec<Call>,
    thread: Option<ScopedJoinHandle<'scope, anyhow::Result<()>>>,
    frames: bool,
}

impl<'scope> Background<'scope> {
    /// Starts the thread in `scope` with `observers`.
    pub fn spawn<'env>(
        scope: &'scope Scope<'scope, 'env>,
        mut observers: Vec<&'scope mut (dyn Observer + Send)>,
    ) -> Self {
        let frames = observers.iter().any(|o| o.wants_frames());
        let (calls, inbox) = sync_channel(QUEUE);
        let thread = scope.spawn(move || serve(&mut observers, &inbox));
        Self {
            calls: Some(calls),
            batch: Vec::with_capacity(BATCH),
            thread: Some(thread),
            frames,
        }
    }

    /// Queues `call`, and hands the batch to the thread once it is full; if the thread has
    /// ended, its error.
    fn send(&mut self, call: Call) -> anyhow::Result<()> {
        self.batch.push(call);
        if self.batch.len() < BATCH {
            return Ok(());
        }
        self.flush()
    }

    /// Hands the batch to the thread; if it has ended, its error.
    fn flush(&mut self) -> anyhow::Result<()> {
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH));
        let sent = self.calls.as_ref().is_some_and(|c| c.send(batch).is_ok());
        if sent { Ok(()) } else { self.join() }
    }

    /// Waits for the thread and returns what it ended with.
    fn join(&mut self) -> anyhow::Result<()> {
        self.calls = None;
        match self.thread.take() {
            Some(thread) => thread.join().unwrap_or_else(|panic| {
                let why = panic
                    .downcast_ref::<&str>()
                    .map(|s| (*s).to_owned())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                Err(anyhow::anyhow!("the output thread panicked: {why}"))
            }),
            None => Err(anyhow::anyhow!("the output thread has already ended")),
        }
    }
}

/// The thread: every call to every observer, in order, until the final one or an error.
fn serve(
    observers: &mut [&mut (dyn Observer + Send)],
    inbox: &Receiver<Vec<Call>>,
) -> anyhow::Result<()> {
    let mut refs = None;
    for call in inbox.iter().flatten() {
        let made;
        let call = match call {
            Call::References(r) => {
                refs = Some(r);
                continue;
            }
            Call::Step(step) => {
                let refs = refs
                    .as_ref()
                    .ok_or_else(|| anyhow::anyhow!("a step came before the references"))?;
                made = Call::Sample(Box::new(step.sample(refs)));
                &made
            }
            ref other => other,
        };
        for o in observers.iter_mut() {
            match call {
                Call::Init(scene) => o.observe_init(scene)?,
                Call::References(_) | Call::Step(_) => {}
                Call::Sample(sample) => o.observe_sample(sample)?,
                Call::Frame(frame) => o.observe_frame(frame)?,
                Call::Event(event) => o.observe_event(event)?,
                Call::Final(report) => o.observe_final(report)?,
            }
        }
        if matches!(call, Call::Final(_)) {
            break;
        }
    }
    Ok(())
}

impl Observer for Background<'_> {
    fn observe_init(&mut self, scene: &Scene) -> anyhow::Result<()> {
        self.send(Call::Init(Box::new(scene.clone())))
    }
    fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()> {
        self.send(Call::Sample(Box::new(*sample)))
    }
    fn makes_samples(&self) -> bool {
        true
    }
    fn observe_references(&mut self, refs: &Arc<References>) -> anyhow::Result<()> {
        self.send(Call::References(Arc::clone(refs)))
    }
    fn observe_step(&mut self, step: &SampleInputs) -> anyhow::Result<()> {
        self.send(Call::Step(Box::new(*step)))
    }
    fn wants_frames(&self) -> bool {
        self.frames
    }
    fn observe_frame(&mut self, frame: &Frame) -> anyhow::Result<()> {
        self.send(Call::Frame(Box::new(frame.clone())))
    }
    fn observe_event(&mut self, event: &Event) -> anyhow::Result<()> {
        self.send(Call::Event(Box::new(event.clone())))
    }
    fn observe_final(&mut self, report: &RunReport) -> anyhow::Result<()> {
        self.batch.push(Call::Final(Box::new(report.clone())));
        self.flush()?;
        self.join()
    }
}

impl Drop for Background<'_> {
    /// A run that ends in an error never sends its final call: the channel's close ends the
    /// thread, which is joined here, its own error or panic set aside for the run's.
    fn drop(&mut self) {
        self.calls = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Records what it is called with; fails at its `fail_at`-th sample.
    #[derive(Default)]
    struct Log {
        /// Every sample's numbers, as bits (a NaN equals itself).
        seen: Vec<Vec<u64>>,
        finals: usize,
        fail_at: Option<usize>,
    }

    impl Observer for Log {
        fn observe_init(&mut self, _scene: &Scene) -> anyhow::Result<()> {
            Ok(())
        }
        fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()> {
            if self.fail_at == Some(self.seen.len()) {
                anyhow::bail!("disk full at sample {}", self.seen.len());
            }
            let fields = crate::output::fields::fields(sample)?;
            self.seen
                .push(fields.into_iter().map(|(_, v)| v.to_bits()).collect());
            Ok(())
        }
        fn observe_final(&mut self, _report: &RunReport) -> anyhow::Result<()> {
            self.finals += 1;
            Ok(())
        }
    }

    fn scene() -> Scene {
        crate::scene::tests::short_yoga(0.05)
    }

    #[test]
    fn the_thread_makes_the_samples_the_loop_would_have_shown() {
        let scene = scene();
        let mut direct = Log::default();
        crate::run::run(&scene, &mut [&mut direct]).unwrap();
        let mut behind = Log::default();
        std::thread::scope(|s| {
            let mut background = Background::spawn(s, vec![&mut behind]);
            crate::run::run(&scene, &mut [&mut background]).unwrap();
        });
        assert!(direct.seen.len() > 10);
        assert_eq!(behind.seen, direct.seen);
        assert_eq!(behind.finals, 1);
    }

    #[test]
    fn an_error_on_the_thread_ends_the_run_with_it() {
        let scene = scene();
        let mut failing = Log {
            fail_at: Some(3),
            ..Log::default()
        };
        let e = std::thread::scope(|s| {
            let mut background = Background::spawn(s, vec![&mut failing]);
            crate::run::run(&scene, &mut [&mut background]).unwrap_err()
        });
        assert!(e.to_string().contains("disk full at sample 3"), "{e:#}");
        assert_eq!(failing.finals, 0);
    }
}
