"""One bake: export (main thread) -> native bakes (any thread) -> write-back (main thread).

    job = BakeJob(context, objects, settings)   # validates and exports; BakeError
    job.run()                                   # or on a worker thread: start_thread()
    stats = job.finish(context)                 # writes; BakeError / Cancelled

``run`` touches no bpy data: it only calls omis on numpy arrays, so the modal
operator can run it on a worker thread while Blender's UI stays responsive.
Nothing is written unless every part of every object baked successfully.
"""

import threading
import time

import numpy as np

from . import export, native, writeback
from .errors import BakeError, Cancelled

# Blender's Bake ▸ Margin ▸ Type -> omis.bake_uv's margin_type.
MARGIN_TYPES = {'EXTEND': "extend", 'ADJACENT_FACES': "adjacent-faces"}


class _Unit:
    """One native bake call: one omis mesh into one image, or onto its corners."""

    def __init__(self, kind, part, target, weight):
        self.kind = kind            # 'uv' or 'corner'
        self.part = part
        self.target = target
        self.weight = float(max(weight, 1))
        self.value = None
        self.noise = None
        self.mask = None
        self.stats = None

    @property
    def label(self):
        name = self.target.name if self.kind == 'uv' else self.target.attribute_name
        return f'{self.part.object_name} → {name}'


class BakeJob:
    def __init__(self, context, objects, settings):
        # A time limit is the bake's whole wall time: export and commit count.
        self.created = time.perf_counter()
        try:
            omis = native.require()
        except RuntimeError as exc:
            raise BakeError(str(exc)) from None
        self.omis = omis
        self.settings = settings
        refused = settings.unsupported()
        if refused is not None:
            raise BakeError(refused)
        objects = _resolve_objects(context, objects)
        self.object_names = [ob.name for ob in objects]
        try:
            self.export = export.export_scene(context, objects, settings.target, omis=omis,
                                              units=native.units)
        except ValueError as exc:  # omis refused some exported value
            raise BakeError(f"export failed: {exc}") from None
        self.units = []
        for target in self.export.images:
            for part in target.parts:
                self.units.append(_Unit('uv', part, target, texels_of(part, target)))
        for target in self.export.attributes:
            for part in target.parts:
                self.units.append(_Unit('corner', part, target, 3 * part.triangles))
        self._total_weight = sum(u.weight for u in self.units) or 1.0
        self._done_weight = 0.0
        self._current = None
        self._cancel = threading.Event()
        self._external_progress = None
        self.fraction = 0.0
        self.started = None        # perf_counter() when run() began
        self.current_label = ""
        self.done = False
        self.cancelled = False
        self.error = None
        self.seconds = 0.0
        self.thread = None
        self.scene_reused = False  # run() baked the last bake's committed omis scene

    # -- control (any thread) --

    def cancel(self):
        self._cancel.set()

    @property
    def cancel_requested(self):
        return self._cancel.is_set()

    def seconds_left(self):
        """Estimated seconds to the end (the time limit when one is set, else the
        elapsed time scaled by the fraction done), or None before there is a basis."""
        if self.started is None or self.fraction <= 0.0:
            return None
        elapsed = time.perf_counter() - self.started
        left = elapsed * (1.0 - self.fraction) / self.fraction
        if self.settings.time_budget > 0:
            since_created = time.perf_counter() - self.created
            left = min(left, max(0.0, self.settings.time_budget - since_created))
        return left

    def _progress(self, fraction):
        unit = self._current
        w = unit.weight if unit is not None else 0.0
        self.fraction = min(1.0, (self._done_weight + w * float(fraction)) / self._total_weight)
        if self._external_progress is not None:
            answer = self._external_progress(self.fraction)
            if answer is not None and not answer:
                self._cancel.set()
        return not self._cancel.is_set()

    # -- the native work (any thread; no bpy) --

    def run(self, progress=None):
        """Commits the scene and bakes every unit. Never raises: sets error/cancelled."""
        self._external_progress = progress
        start = self.started = time.perf_counter()
        s = self.settings
        omis = self.omis
        try:
            scene = self.export.scene.committed()   # the last bake's, when unchanged
            self.scene_reused = self.export.scene.reused
            common = dict(strategy=s.strategy, beta=float(s.power_beta),
                          cutoff=float(s.cutoff_threshold), samples=int(s.samples),
                          seed=int(s.seed), smooth_normals=True,
                          noise_target=float(s.noise_target) if s.use_noise_target else None,
                          progress=self._progress)
            margin_type = MARGIN_TYPES[s.margin_type]
            names = s.technique_names()
            if names is not None:
                common["techniques"] = names
            remaining_weight = self._total_weight
            for unit in self.units:
                if self._cancel.is_set():
                    raise omis.Cancelled("bake: cancelled")
                self._current = unit
                self.current_label = unit.label
                budget = None
                if s.time_budget > 0:
                    left = s.time_budget - (time.perf_counter() - self.created)
                    budget = max(left * unit.weight / remaining_weight, 1e-3)
                if unit.kind == 'uv':
                    result = omis.bake_uv(scene, unit.part.mesh_id,
                                          unit.target.width, unit.target.height,
                                          margin=int(s.margin), margin_type=margin_type,
                                          time_budget=budget, **common)
                else:
                    result = omis.bake_vertices(scene, unit.part.mesh_id,
                                                domain="CORNER", time_budget=budget, **common)
                unit.value = np.array(result.value, np.float32)
                unit.mask = np.array(result.mask, np.float32)
                unit.noise = np.array(result.noise, np.float32)
                unit.stats = dict(result.stats)
                self._done_weight += unit.weight
                remaining_weight -= unit.weight
                self.fraction = self._done_weight / self._total_weight
            self._current = None
        except omis.Cancelled:
            self.cancelled = True
        except KeyboardInterrupt:
            self.cancelled = True
        except Exception as exc:  # reported to the artist, never half-written
            self.error = f"{type(exc).__name__}: {exc}" if not isinstance(
                exc, (ValueError, RuntimeError)) else str(exc)
        finally:
            self.seconds = time.perf_counter() - start
            self.done = True

    def start_thread(self):
        """Runs run() on a daemon worker thread; poll .done / .fraction from the main thread."""
        self.thread = threading.Thread(target=self.run, name="omis-bake", daemon=True)
        self.thread.start()
        return self.thread

    # -- results (main thread) --

    def finish(self, context):
        """Writes every result, stores the summary in scene.omis, returns the stats dict."""
        if self.thread is not None:
            self.thread.join()
        if not self.done:
            raise RuntimeError("finish() before the bake ran")
        if self.cancelled:
            raise Cancelled("bake cancelled: no image or attribute was changed")
        if self.error is not None:
            raise BakeError(f"bake failed: {self.error} (no image or attribute was changed)")
        s = self.settings
        writers = []
        try:
            for target in self.export.images:
                parts = [(u.value, u.mask) for u in self.units
                         if u.kind == 'uv' and u.target is target]
                writers.append(writeback.prepare_image(target, parts, int(s.margin),
                                                       bool(s.use_clear)))
            for target in self.export.attributes:
                parts = [(u.value, u.part.tri_loops) for u in self.units
                         if u.kind == 'corner' and u.target is target]
                writers.append(writeback.prepare_attribute(target, parts))
        except (ReferenceError, ValueError) as exc:
            raise BakeError(f"cannot write the results: {exc} (nothing was changed)") from None
        for write in writers:
            write()
        stats = self.stats()
        store = context.scene.omis
        store.last_status = stats["status"]
        store.last_seconds = stats["seconds"]
        store.last_samples_per_texel = stats["samples_per_texel"]
        store.last_mean_error = stats["mean_relative_error"]
        store.last_error_p95 = stats["error_p95"]
        store.last_halving_seconds = stats["halving_seconds"]
        store.last_halving_measured = stats["halving_measured"]
        store.last_error_measured = stats["error_measured"]
        store.last_plan = stats["plan"]
        store.last_target = stats["target"]
        # Every warning the stats carry reaches the panel, whatever added it.
        store.last_warnings = "\n".join(" ".join(str(w).split()) for w in stats["warnings"])
        return stats

    def _errors(self):
        """Relative errors (noise) of every baked texel or corner, all units together."""
        parts = []
        for u in self.units:
            if u.noise is None:
                continue
            noise = u.noise.reshape(-1)
            mask = u.mask.reshape(-1) > 0 if u.mask is not None else np.ones(noise.shape, bool)
            parts.append(noise[mask])
        return np.concatenate(parts) if parts else np.zeros(0, np.float32)

    def stats(self):
        units = [u for u in self.units if u.stats is not None]
        covered = sum(u.stats.get("covered", 0) for u in units)
        samples = sum(u.stats.get("samples", 0) for u in units)
        draws = sum(u.stats.get("draws", 0) for u in units)
        statuses = [u.stats.get("status", "complete") for u in units]
        if "time budget reached" in statuses:
            status = "time budget reached"
        elif statuses and all(st == "noise target reached" for st in statuses):
            status = "noise target reached"
        else:
            status = "complete"
        mean_error = (sum(u.stats["mean_relative_error"] * u.stats.get("covered", 0)
                          for u in units) / covered) if covered else 0.0
        s = self.settings
        buried = buried_texels(units)
        errors = self._errors()
        sampling = sum(u.stats.get("seconds", 0.0) for u in units)
        return {
            "status": status,
            "seconds": self.seconds,
            "bake_seconds": sampling,
            **accuracy_cost(errors, self.seconds, [u.stats for u in units]),
            "samples": samples,
            "rays_traced": sum(u.stats.get("rays_traced", 0) for u in units),
            "covered": covered,
            "samples_per_texel": samples / covered if covered else 0.0,
            # The work behind the samples: texels whose centre sees no light
            # draw more per sample (README, "Baking").
            "draws_per_texel": draws / covered if covered else 0.0,
            "shadowed_texels": sum(u.stats.get("shadowed_texels", 0) for u in units),
            # Texels inside other geometry or on coinciding faces, per object
            # (dark, as Cycles bakes them: overlapping props to look at).
            "buried_texels": buried,
            "mean_relative_error": mean_error,
            # A noise threshold measures the error from independent streams;
            # otherwise each texel's one sequence leaves an upper estimate.
            "error_measured": bool(s.use_noise_target),
            "max_relative_error": max((u.stats["max_relative_error"] for u in units),
                                      default=0.0),
            "passes": max((u.stats.get("passes", 0) for u in units), default=0),
            "plan": units[0].stats.get("plan", "") if units else "",
            "strategy": s.strategy,
            "techniques": s.technique_names(),
            "target": s.target,
            "objects": list(self.object_names),
            "images": [t.name for t in self.export.images],
            "attributes": [f"{t.object_name}:{t.attribute_name}" for t in self.export.attributes],
            "units": [dict(u.stats, label=u.label) for u in units],
            # Buried texels are warnings too: the panel, the reports and the
            # status line list them with the exporter's.
            "warnings": list(self.export.warnings) + buried_report(buried, s.target),
            "exported": dict(self.export.counts),
        }


def buried_texels(units):
    """{object name: texels (corners) lying inside other objects or on their faces}, for the
    objects that have any, in bake order."""
    out = {}
    for u in units:
        n = int(u.stats.get("buried_texels", 0))
        if n:
            out[u.part.object_name] = out.get(u.part.object_name, 0) + n
    return out


def buried_report(buried, target='IMAGE_TEXTURES'):
    """One line per object of buried_texels(): 'N texels of "Crate.003" lie inside other
    objects'."""
    what = "texels" if target == 'IMAGE_TEXTURES' else "corners"
    return [f'{n} {what} of "{name}" lie inside other objects (or on their faces): they bake '
            f'dark, as in Cycles' for name, n in buried.items()]


def texels_of(part, target):
    """About how many texels of target's image a part covers: what its bake costs.
    A time limit and the progress bar share the bake out by these weights, so
    objects sharing an image take time in proportion to their texels (equal
    shares gave a small object many times the samples of a large one)."""
    return min(max(part.uv_area, 0.0), 1.0) * target.width * target.height


def accuracy_cost(errors, seconds, unit_stats):
    """What the accuracy reached cost, and what halving it would cost.

    errors: the texels' relative errors (estimated standard error / value);
    seconds: the whole bake; unit_stats: the native bakes' statistics (omis'
    BakeResult.stats), one per object part.

    Each native bake predicts from its own measured convergence — error ∝ t^(-β)
    fitted over its later passes — the sampling time that would halve its mean
    error (halving_seconds). Halving every part's error halves the mean over all
    texels, so the bake needs their sum; export and write-back are not repeated.
    A bake with a sample budget alone runs one pass and measures no convergence:
    it assumes β = 0.5 (error ∝ 1/√n, independent draws), and since omis'
    low-discrepancy draws converge at least that fast (16 → 64 samples gave 0.31×
    the error on the test floor, not 0.5×) the figure is then an upper bound;
    halving_measured says which.
    """
    errors = np.asarray(errors, np.float64)
    has = errors.size > 0
    halving = float(sum(u.get("halving_seconds", 0.0) for u in unit_stats))
    return {
        "error_mean": float(errors.mean()) if has else 0.0,
        # The smallest error that 95 % of the texels do not exceed (no interpolation).
        "error_p95": float(np.percentile(errors, 95, method='higher')) if has else 0.0,
        "halving_seconds": halving,
        "halving_total_seconds": float(seconds) + halving,
        "halving_measured": bool(unit_stats) and all(u.get("halving_measured", False)
                                                     for u in unit_stats),
    }


def _resolve_objects(context, objects):
    """Objects from objects or names (default: the selected objects); names must exist."""
    if objects is None:
        return list(context.selected_objects)
    if isinstance(objects, str):
        objects = [objects]
    out = []
    for item in objects:
        if isinstance(item, str):
            ob = context.scene.objects.get(item)
            if ob is None:
                raise BakeError(f'objects: no object named "{item}" in the scene')
            item = ob
        out.append(item)
    return out


def bake(context, objects=None, *, progress=None, **settings):
    """Bakes `objects` (default: the selected objects) with omis; returns the stats dict.

    objects: objects or their names.
    settings: any of scene.omis' settings (use_optimal_mis, optimal_mode,
    heuristic, power_beta, cutoff_threshold, technique_mode, techniques,
    samples, time_budget, use_noise_target, noise_target, seed; the rest come
    from context.scene.omis) and of Blender's bake settings (target, margin,
    margin_type, use_clear, use_selected_to_active; the rest come from
    context.scene.render.bake). techniques takes identifiers
    ('UNOCCLUDED_SOLID_ANGLE') or SPEC names ('unoccluded/solid-angle'); giving
    techniques implies technique_mode='MANUAL'.
    progress: optional callable(fraction) -> bool, called on this thread;
    returning False cancels. Raises BakeError or Cancelled; on either, no image
    or attribute is changed. Runs synchronously (also in background mode).
    The returned dict includes error_mean and error_p95 (the texels' relative
    error), seconds, halving_seconds (extra sampling time to halve the mean error)
    and halving_measured (True: estimated from the bake's measured convergence,
    which a time limit or noise threshold gives; False: the 1/√n upper bound).
    """
    from .settings import settings_from
    try:
        s = settings_from(context.scene.omis, settings)
    except ValueError as exc:
        raise BakeError(str(exc)) from None
    job = BakeJob(context, objects, s)
    job.run(progress=progress)
    return job.finish(context)
