//! `oeg._oeg`: the native half of the `oeg` Python package. It wraps the `oeg` and `oeg-eval` crates and holds
//! no logic of its own: arrays are checked and converted here, everything else is the crates' code. The
//! Python half (`python/oeg/`) turns results into dicts and DataFrames; `python/oeg/_oeg.pyi` types both.
//!
//! Long work (integrating, planning, running a scenario) runs with the GIL released.

mod convert;
mod map;
mod scenario;

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(
    _oeg,
    OegError,
    PyException,
    "A map, scenario or data file the testbed refused: the message names the file, the place and what was expected."
);

fn oeg_error(e: impl std::fmt::Display) -> PyErr {
    OegError::new_err(e.to_string())
}

/// Runs `work` on a thread of its own with the GIL released, while this thread checks Python's signals every
/// 50 ms: on Ctrl-C the work is cancelled at its next step ([`oeg_eval::progress::Progress::cancel`]) and the
/// call raises `KeyboardInterrupt` once it has stopped.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(&oeg_eval::progress::Progress) -> oeg_eval::error::Result<T> + Send,
) -> PyResult<T> {
    let progress = oeg_eval::progress::Progress::hidden();
    let (result, interrupt) = py.detach(|| {
        std::thread::scope(|scope| {
            // The worker says when it is done, so a short call returns at once; signals are checked every 50 ms
            // while it runs.
            let (done, finished) = std::sync::mpsc::channel::<()>();
            let progress = &progress;
            let worker = scope.spawn(move || {
                let result = work(progress);
                let _ = done.send(());
                result
            });
            let mut interrupt = None;
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
                finished.recv_timeout(std::time::Duration::from_millis(50))
            {
                if interrupt.is_none()
                    && let Err(e) = Python::attach(|py| py.check_signals())
                {
                    progress.cancel();
                    interrupt = Some(e);
                }
            }
            (worker.join(), interrupt)
        })
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    match result {
        Ok(r) => r.map_err(oeg_error),
        Err(_) => Err(OegError::new_err(
            "the work panicked: this is a bug, please report it",
        )),
    }
}

/// The native module.
#[pymodule]
fn _oeg(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<map::PyMap>()?;
    m.add_class::<scenario::PyTruth>()?;
    m.add("OegError", m.py().get_type::<OegError>())?;
    m.add_function(wrap_pyfunction!(map::load, m)?)?;
    m.add_function(wrap_pyfunction!(map::read_graph, m)?)?;
    m.add_function(wrap_pyfunction!(map::read_pcd, m)?)?;
    m.add_function(wrap_pyfunction!(map::plan, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::run_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::truth, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::score, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
