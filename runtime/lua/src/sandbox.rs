//! The limits a script runs under, made so that a script cannot catch them.
//!
//! Each resume (of a behavior, a test, a handler, a `wait_until` condition, a scene's top
//! level) gets an instruction budget and a memory allowance, under a cap on the whole Lua
//! heap of the scene. Lua raises a limit as an ordinary error, which `pcall`, `xpcall` and
//! `coroutine.resume` would catch; so the first limit hit *trips* the sandbox until the
//! resume ends: the instruction hook raises again at once on every later check, and the
//! prelude's `pcall`, `xpcall`, `coroutine.resume` and `coroutine.close` re-raise the
//! limit's message (see `prelude.lua`) instead of returning it. The message names the
//! limit and the `file:line` where it was hit.

use mlua::{HookTriggers, Lua, MultiValue, Value, VmState};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

/// Limits on what a script may do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScriptLimits {
    /// VM instructions one resume (or handler call) may execute before it is stopped.
    pub instructions: u64,
    /// Bytes one resume may add to the Lua heap before allocation fails.
    pub memory: usize,
    /// Bytes the whole Lua heap of a scene may hold (every behavior, handler and global
    /// together); a resume that would grow it further fails.
    pub heap: usize,
}

impl Default for ScriptLimits {
    fn default() -> Self {
        ScriptLimits {
            instructions: 5_000_000,
            memory: 16 << 20,
            heap: 256 << 20,
        }
    }
}

/// How often (in VM instructions) the hook counts.
const HOOK_EVERY: u32 = 1000;
/// Heap lent above a tripped memory limit, so that the script can unwind (make the
/// message, leave its `pcall`s) without failing to allocate again.
const UNWIND_HEAP: usize = 1 << 20;

/// The state of the limits for the resume under way, shared with the instruction hook.
#[derive(Debug)]
pub(crate) struct Sandbox {
    limits: ScriptLimits,
    instructions: AtomicU64,
    /// The limit the resume under way hit, with its location; `None` until then.
    tripped: Mutex<Option<String>>,
    /// Whether the current memory limit is the scene's heap cap rather than the resume's
    /// allowance (to name the right one).
    heap_bound: std::sync::atomic::AtomicBool,
}

impl Sandbox {
    /// A sandbox of `limits`, its instruction hook installed on `lua`.
    pub(crate) fn install(lua: &Lua, limits: ScriptLimits) -> mlua::Result<Arc<Sandbox>> {
        let sandbox = Arc::new(Sandbox {
            limits,
            instructions: AtomicU64::new(0),
            tripped: Mutex::new(None),
            heap_bound: false.into(),
        });
        let hook = sandbox.clone();
        lua.set_global_hook(
            HookTriggers::new().every_nth_instruction(HOOK_EVERY),
            move |_, debug| {
                if let Some(msg) = hook.tripped() {
                    return Err(mlua::Error::runtime(msg));
                }
                let used = hook
                    .instructions
                    .fetch_add(HOOK_EVERY as u64, Ordering::Relaxed)
                    + HOOK_EVERY as u64;
                if used <= hook.limits.instructions {
                    return Ok(VmState::Continue);
                }
                let source = debug.source();
                let place = location(source.short_src.as_deref(), debug.current_line());
                Err(mlua::Error::runtime(hook.trip(hook.budget_message(&place))))
            },
        )?;
        let limit = sandbox.clone();
        let check = lua.create_function(move |lua, err: Value| {
            let memory = match &err {
                Value::Error(e) => matches!(root(e), mlua::Error::MemoryError(_)),
                Value::String(s) => s.as_bytes().as_ref() == b"not enough memory",
                _ => false,
            };
            if memory && limit.tripped().is_none() {
                // The caller of the pcall that caught it: level 0 is this function, 1 the
                // prelude's wrapper.
                let place = lua
                    .inspect_stack(2, |d| {
                        location(d.source().short_src.as_deref(), d.current_line())
                    })
                    .unwrap_or_default();
                limit.trip(format!("{place}{}", limit.memory_message(lua)));
                let _ = lua.set_memory_limit(lua.used_memory() + UNWIND_HEAP);
            }
            if let Some(msg) = limit.tripped() {
                return Ok(MultiValue::from_vec(vec![Value::String(
                    lua.create_string(msg)?,
                )]));
            }
            let clean = match &err {
                Value::Error(e) => Value::String(lua.create_string(clean_message(e))?),
                _ => err,
            };
            Ok(MultiValue::from_vec(vec![Value::Nil, clean]))
        })?;
        lua.globals().raw_set("__troupe_limit", check)?;
        Ok(sandbox)
    }

    /// What an exceeded instruction budget says, hit at `place` (`file:line: `).
    fn budget_message(&self, place: &str) -> String {
        format!(
            "{place}instruction budget exceeded: a resume may run {} VM instructions \
             (--instruction-budget; runaway loop?)",
            self.limits.instructions
        )
    }

    /// Charges `instructions` of work done inside Lua's C library (a string function's
    /// pass over its subject, which the hook does not count) to the resume under way;
    /// returns the limit's message, tripping it, once the budget is spent.
    pub(crate) fn charge(&self, lua: &Lua, instructions: u64) -> Option<String> {
        let used = self.instructions.fetch_add(instructions, Ordering::Relaxed) + instructions;
        if let Some(msg) = self.tripped() {
            return Some(msg);
        }
        if used <= self.limits.instructions {
            return None;
        }
        // Level 0 is the string function, 1 the script that called it.
        let place = lua
            .inspect_stack(1, |d| {
                location(d.source().short_src.as_deref(), d.current_line())
            })
            .unwrap_or_default();
        Some(self.trip(self.budget_message(&place)))
    }

    fn tripped(&self) -> Option<String> {
        self.tripped
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }

    /// Records the first limit hit in this resume, and returns its message.
    fn trip(&self, msg: String) -> String {
        self.tripped
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .get_or_insert(msg)
            .clone()
    }

    /// What a memory failure says: the allowance of a resume, or the scene's heap cap.
    fn memory_message(&self, lua: &Lua) -> String {
        if self.heap_bound.load(Ordering::Relaxed) {
            format!(
                "Lua heap full: the scene's scripts may hold {} bytes together \
                 (--lua-memory; now {} bytes)",
                self.limits.heap,
                lua.used_memory()
            )
        } else {
            format!(
                "memory limit exceeded: a resume may add {} bytes to the Lua heap \
                 (--memory-limit)",
                self.limits.memory
            )
        }
    }

    /// Runs `f` (one resume) under the instruction budget, the memory allowance and the
    /// heap cap. A limit hit inside comes back as the error, with its location, whatever
    /// the script did to catch it.
    pub(crate) fn guarded<R>(
        &self,
        lua: &Lua,
        f: impl FnOnce() -> mlua::Result<R>,
    ) -> Result<R, Failure> {
        self.instructions.store(0, Ordering::Relaxed);
        *self.tripped.lock().unwrap_or_else(|p| p.into_inner()) = None;
        let allowance = lua.used_memory().saturating_add(self.limits.memory);
        self.heap_bound
            .store(allowance >= self.limits.heap, Ordering::Relaxed);
        // A failure to set the limit only means allocation is unbounded for this call.
        let _ = lua.set_memory_limit(allowance.min(self.limits.heap));
        let result = f();
        let tripped = self
            .tripped
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take();
        let failure = match (result, tripped) {
            (Ok(r), None) => return self.relax(lua, Ok(r)),
            (_, Some(msg)) => Failure::Limit(msg),
            (Err(e), None) => match root(&e) {
                mlua::Error::MemoryError(_) => Failure::Memory(self.memory_message(lua)),
                _ => Failure::Error(crate::error_value::explain(lua, describe(&e))),
            },
        };
        self.relax(lua, Err(failure))
    }

    /// Between resumes, only the heap cap holds; memory a failed resume left is
    /// collected.
    fn relax<R>(&self, lua: &Lua, r: Result<R, Failure>) -> Result<R, Failure> {
        crate::error_value::forget(lua);
        if matches!(r, Err(Failure::Limit(_) | Failure::Memory(_))) {
            let _ = lua.set_memory_limit(0);
            let _ = lua.gc_collect();
        }
        let _ = lua.set_memory_limit(self.limits.heap.max(lua.used_memory()));
        r
    }
}

/// Why a guarded call failed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Failure {
    /// A limit, its message naming it and where it was hit.
    Limit(String),
    /// A memory limit hit where Lua reports no place (see [`Failure::located`]).
    Memory(String),
    /// A script error, with its location and traceback.
    Error(String),
}

impl Failure {
    /// The message, with `place` (`file:line: `) in front of a memory limit.
    pub(crate) fn located(self, place: Option<String>) -> String {
        match self {
            Failure::Memory(m) => format!("{}{m}", place.unwrap_or_default()),
            Failure::Limit(m) | Failure::Error(m) => m,
        }
    }

    /// The message (a memory limit without its place).
    pub(crate) fn message(self) -> String {
        self.located(None)
    }
}

/// `file:line: ` of a Lua location, or nothing when unknown.
fn location(short_src: Option<&str>, line: Option<usize>) -> String {
    match (short_src, line) {
        (Some(src), Some(line)) if line > 0 => format!("{src}:{line}: "),
        (Some(src), _) => format!("{src}: "),
        _ => String::new(),
    }
}

/// The innermost error of a chain of callback errors.
fn root(e: &mlua::Error) -> &mlua::Error {
    match e {
        mlua::Error::CallbackError { cause, .. } | mlua::Error::WithContext { cause, .. } => {
            root(cause)
        }
        other => other,
    }
}

/// The text of an error as a script sees it once caught: the message alone, without
/// mlua's `runtime error:` prefix or the traceback (which stays in the error a failed
/// behavior reports).
pub(crate) fn clean_message(e: &mlua::Error) -> String {
    match e {
        mlua::Error::CallbackError { traceback, cause } => {
            format!(
                "{}{}",
                caller_place(traceback),
                crate::args::error_text(cause)
            )
        }
        other => crate::args::error_text(other),
    }
}

/// `file:line: ` of the script line that called a Rust function, read from the traceback
/// of its error (the first frame of a script; the prelude's wrappers and mlua's own
/// chunks, such as the `__mlua_index` that looks up a handle's fields, are skipped), so
/// that a refused call names its place as Lua's own errors do.
fn caller_place(traceback: &str) -> String {
    traceback
        .lines()
        .map(str::trim)
        .filter(|l| {
            !l.starts_with("[C]") && !l.starts_with("prelude:") && !l.starts_with("__mlua_")
        })
        .find_map(|l| {
            let (place, _) = l.split_once(": in ")?;
            place.rsplit_once(':')?.1.parse::<u32>().ok()?;
            Some(format!("{place}: "))
        })
        .unwrap_or_default()
}

/// A readable error: the message in troupe's wording, then the traceback when there is
/// one.
pub(crate) fn describe(e: &mlua::Error) -> String {
    match e {
        mlua::Error::CallbackError { traceback, cause } => {
            format!(
                "{}{}\n{traceback}",
                caller_place(traceback),
                describe(cause)
            )
        }
        mlua::Error::WithContext { context, cause } => {
            format!("{context}: {}", describe(cause))
        }
        other => crate::args::error_text(other),
    }
}

/// Where the coroutine `thread` stopped (its innermost Lua frame), as `file:line: `: for a
/// memory failure, which Lua reports without a place.
pub(crate) fn thread_location(thread: &mlua::Thread) -> Option<String> {
    use mlua::ffi;
    let state = thread.state();
    // SAFETY: the thread is alive (we hold a reference) and not running; lua_getstack
    // and lua_getinfo only read its call information, which an error leaves in place.
    unsafe {
        for level in 0..8 {
            let mut ar: ffi::lua_Debug = std::mem::zeroed();
            if ffi::lua_getstack(state, level, &mut ar) == 0 {
                return None;
            }
            if ffi::lua_getinfo(state, c"Sl".as_ptr(), &mut ar) == 0 {
                return None;
            }
            if ar.currentline > 0 {
                let src = std::ffi::CStr::from_ptr(ar.short_src.as_ptr()).to_string_lossy();
                return Some(location(Some(&src), Some(ar.currentline as usize)));
            }
        }
    }
    None
}
