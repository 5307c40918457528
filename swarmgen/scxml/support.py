"""The ECMAScript support scripts of an emitted SCXML document (`$sg`, docs/scxml.md): what
makes Qt SCXML's ECMAScript agree with swarmgen's Python runtime. `emit` puts the base script in
every document and each extension only in a document that needs it, so others keep their bytes."""

from __future__ import annotations

from swarmgen.runtime.chart import STEP_BOUND

# The support script every document carries (docs/scxml.md): what makes ECMAScript agree with
# swarmgen's Python runtime. A zero divisor and a field the event does not carry are errors
# (error.execution, the guard is false) instead of Infinity and `undefined`; `value` reads a
# behaviour's output with the value rule (what is missing takes its zero, recursively).
SUPPORT_SCRIPT = """
var $sg = {
  div: function (a, b) {
    if (b == 0) { throw new RangeError("division by zero"); }
    return a / b;
  },
  mod: function (a, b) {
    if (b == 0) { throw new RangeError("modulo by zero"); }
    return ((a % b) + b) % b;
  },
  field: function (e, f) {
    var d = (e !== undefined && e !== null) ? e.data : undefined;
    if (d === undefined || d === null || typeof d !== "object" ||
        !Object.prototype.hasOwnProperty.call(d, f)) {
      throw new TypeError("the event has no field " + f);
    }
    return d[f];
  },
  value: function (d, f, zero) {
    var v = (d !== undefined && d !== null && typeof d === "object") ? d[f] : undefined;
    return $sg.fill(v, zero);
  },
  fill: function (v, t) {
    if (t === null || typeof t !== "object" || Array.isArray(t)) {
      return (v === undefined || v === null) ? t : v;
    }
    var g = (v !== undefined && v !== null && typeof v === "object" &&
             !Array.isArray(v)) ? v : {};
    var r = {};
    for (var f in t) { r[f] = $sg.fill(g[f], t[f]); }
    return r;
  }
};
"""
# The step bound (docs/semantics.md), only in a document with bounded transitions (so others
# keep their bytes). A bounded transition's cond ends with `$sg.spin()`: it counts, throws once
# past the bound (Qt raises error.execution and the cond is false), then stays false until the
# count restarts. Every cond of such a document starts with `$sg.tick()`, which restarts
# it at the first transition considered under a new input from outside, exactly where the
# engine restarts it (`Engine._restart_count`); not under an event the document sent itself
# (`<send target="#_internal">`, a `raise` with data: timers have a sendid, those have none).
# It reads `_event` itself, after `typeof`: before the first event Qt has no `_event`, and a
# cond naming it would throw (an error.execution the engine never raises).
STEP_SCRIPT = f"""
$sg.bound = {STEP_BOUND};
$sg.steps = 0;
$sg.hit = false;
$sg.last = null;
$sg.tick = function () {{
  var e = typeof _event === "undefined" ? null : _event;
  if (e !== undefined && e !== null && e.type === "external" && e !== $sg.last &&
      !(e.origin === "#_internal" && !e.sendid)) {{
    $sg.last = e;
    $sg.steps = 0;
    $sg.hit = false;
  }}
  return true;
}};
$sg.spin = function () {{
  $sg.steps += 1;
  if ($sg.steps <= $sg.bound) {{ return true; }}
  if (!$sg.hit) {{
    $sg.hit = true;
    throw new RangeError("more than " + $sg.bound + " steps without an external event");
  }}
  return false;
}};
"""
# Delays computed at run time (`raise e after n s`), only in a document that has one: a delay
# must be a number of at least 0 (in ms or s) or a duration string, else the `<send>` raises
# error.execution and sends nothing, as the engine does (`Engine.raise_delayed`,
# `runtime.chart.duration_ms`).
DELAY_SCRIPT = r"""
$sg.delay = function (v, scale) {
  if (typeof v !== "number" || !(v >= 0) || v === Infinity) {
    throw new TypeError("the delay " + v + " is not a duration");
  }
  return Math.round(v * scale) + "ms";
};
$sg.duration = function (v) {
  var m = (typeof v === "string") ? /^\s*(\d+(\.\d*)?|\.\d+)(ms|s)\s*$/.exec(v) : null;
  if (m === null) {
    throw new TypeError("the delay " + v + " is not a duration such as '2s' or '500ms'");
  }
  return Math.round(parseFloat(m[1]) * (m[3] === "s" ? 1000 : 1)) + "ms";
};
"""
# `_event.<field>` (only in a document that reads one): W3C's fields as the engine gives them
# (`runtime.host.event_fields`): "" where Qt SCXML leaves a field undefined, `{}` for no data,
# the processor's type only with an origin (Qt also gives it to error.execution).
META_SCRIPT = """
$sg.meta = function (e, f) {
  if (e === undefined || e === null) { throw new ReferenceError("_event is not bound yet"); }
  var sent = e.origin !== undefined && e.origin !== null && e.origin !== "";
  if (f === "data") {
    return (e.data === undefined || e.data === null || e.data === "") ? {} : e.data;
  }
  if (f === "origintype") { return sent ? "http://www.w3.org/TR/scxml/#SCXMLEventProcessor" : ""; }
  var v = e[f];
  return (v === undefined || v === null) ? "" : v;
};
"""
# `raise e(value)` (only in a document that has one): Qt SCXML gives a `<content expr>` as its
# text (the number 123 arrives as "123", a list as ""), where W3C's ECMAScript datamodel and the
# engine give the value itself. So the document sends the value as JSON behind a marker no
# model string starts with (a NUL), and `$sg.meta(_event, "data")` reads it back as the value.
CONTENT_SCRIPT = r"""
$sg.boxed = "\u0000sg.content:";
$sg.content = function (v) { return $sg.boxed + JSON.stringify(v); };
if ($sg.meta !== undefined) {
  $sg.unboxed = $sg.meta;
  $sg.meta = function (e, f) {
    var v = $sg.unboxed(e, f);
    return (f === "data" && typeof v === "string" && v.indexOf($sg.boxed) === 0) ?
      JSON.parse(v.substring($sg.boxed.length)) : v;
  };
}
"""
# A location the document reads that is none (`invalid("x")`, only in a document that has one:
# an SCXML input's undeclared reference): it throws, so Qt SCXML raises error.execution as the
# engine does (`runtime.chart.Context.invalid`, W3C 5.4, 5.9, 6.4).
INVALID_SCRIPT = """
$sg.invalid = function (l) { throw new ReferenceError(l + " is not a valid location"); };
"""
INVALID_CALL = "$sg.invalid("
# `startswith(text, prefix)` (only in a document that has one): both strings, else it throws
# (error.execution), as the engine's `Context.startswith`.
STARTS_SCRIPT = """
$sg.startswith = function (t, p) {
  if (typeof t !== "string" || typeof p !== "string") {
    throw new TypeError("startswith takes strings");
  }
  return t.substring(0, p.length) === p;
};
"""
STARTS_CALL = "$sg.startswith("
TICK = "$sg.tick()"
SPIN = "$sg.spin()"
