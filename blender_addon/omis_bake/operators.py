"""bpy.ops.omis.bake: modal with a worker thread when invoked from the UI, synchronous
when executed (scripts, background mode)."""

import bpy

from . import job as job_module
from .errors import BakeError, Cancelled
from .settings import ARGUMENT_NAMES, operator_annotations, settings_from

# The bake running in the UI, if any (read by the panel).
running = None


def _redraw_properties(context):
    screen = context.screen
    if screen is None:
        return
    for area in screen.areas:
        if area.type == 'PROPERTIES':
            area.tag_redraw()


def _redraw_all(context):
    screen = context.screen
    if screen is not None:
        for area in screen.areas:
            area.tag_redraw()


def format_seconds(seconds):
    """'42 s', '3 min 5 s', '2 h 10 min': a duration as an artist reads it."""
    seconds = max(0.0, float(seconds))
    if seconds < 10:
        return f"{seconds:.1f} s"
    if seconds < 60:
        return f"{seconds:.0f} s"
    if seconds < 3600:
        return f"{int(seconds // 60)} min {int(seconds % 60)} s"
    return f"{int(seconds // 3600)} h {int(seconds % 3600 // 60)} min"


def accuracy_line(stats):
    """The accuracy reached and what halving it costs, in one sentence."""
    more = format_seconds(stats["halving_seconds"])
    halving = (f"an estimated {more} more (from the bake's convergence)"
               if stats["halving_measured"] else f"at most {more} more")
    bound = "" if stats.get("error_measured") else "≤ "
    return (f'error {bound}{100 * stats["error_mean"]:.2f} % mean, {100 * stats["error_p95"]:.2f} % '
            f'for 95 % of texels; halving it: {halving}')


def _report_stats(op, stats):
    for warning in stats["warnings"]:
        op.report({'WARNING'}, warning)
    for line in job_module.buried_report(stats.get("buried_texels", {}), stats.get("target")):
        op.report({'WARNING'}, line)
    if stats["images"]:
        op.report({'INFO'}, "Baked into " + ", ".join(f'"{n}"' for n in stats["images"])
                  + ": save the images or pack them")
    op.report({'INFO'},
              f'omis bake: {format_seconds(stats["seconds"])}, '
              f'{stats["samples_per_texel"]:.0f} samples per texel, {accuracy_line(stats)} '
              f'({stats["status"]})')


def progress_text(job):
    """'42 % — about 12 s left (Plane → img)'."""
    if job.cancel_requested:
        return "cancelling…"
    text = f"{100 * job.fraction:.0f} %"
    left = job.seconds_left()
    if left is not None:
        text += f" — about {format_seconds(left)} left"
    if job.current_label:
        text += f" ({job.current_label})"
    return text


class OMIS_OT_bake(bpy.types.Operator):
    """Bake direct lighting of the selected meshes with omis (optimal multiple importance
    sampling) into their active image textures or color attributes"""
    bl_idname = "omis.bake"
    bl_label = "Bake (omis)"
    bl_options = {'REGISTER'}

    __annotations__ = operator_annotations()

    @classmethod
    def poll(cls, context):
        if running is not None:
            cls.poll_message_set("an omis bake is already running")
            return False
        return True

    def _settings(self, context):
        overrides = {name: getattr(self, name) for name in ARGUMENT_NAMES
                     if self.properties.is_property_set(name)}
        return settings_from(context.scene.omis, overrides)

    def _new_job(self, context):
        try:
            return job_module.BakeJob(context, None, self._settings(context))
        except (BakeError, ValueError) as exc:
            self.report({'ERROR'}, str(exc))
            return None

    def _finish(self, context, job, interactive=False):
        try:
            stats = job.finish(context)
        except Cancelled as exc:
            self.report({'WARNING'}, str(exc))
            return {'CANCELLED'}
        except BakeError as exc:
            self.report({'ERROR'}, str(exc))
            return {'CANCELLED'}
        _report_stats(self, stats)
        if interactive:
            # An undo step for the written color attributes, without the redo
            # panel a REGISTER|UNDO operator would get (it would re-bake on every
            # tweak, blocking the UI).
            bpy.ops.ed.undo_push(message="omis Bake")
            _redraw_all(context)
        return {'FINISHED'}

    def execute(self, context):
        job = self._new_job(context)
        if job is None:
            return {'CANCELLED'}
        job.run()
        return self._finish(context, job)

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        global running
        job = self._new_job(context)
        if job is None:
            return {'CANCELLED'}
        self._job = job
        running = job
        job.start_thread()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        # The window manager's progress (Blender's bake uses the same), in per mille.
        wm.progress_begin(0, 1000)
        self._progress_open = True
        self._status(context, "starting")
        return {'RUNNING_MODAL'}

    def _status(self, context, text):
        if context.workspace is not None:
            context.workspace.status_text_set(
                None if text is None else f"omis bake: {text} — Esc to cancel")
        _redraw_properties(context)

    def _stop(self, context):
        global running
        wm = context.window_manager
        if getattr(self, "_timer", None) is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        if getattr(self, "_progress_open", False):
            wm.progress_end()
            self._progress_open = False
        running = None
        self._status(context, None)

    def modal(self, context, event):
        job = self._job
        if event.type == 'ESC' and event.value == 'PRESS' and not job.cancel_requested:
            job.cancel()
            self._status(context, "cancelling…")
            return {'RUNNING_MODAL'}
        if event.type == 'TIMER':  # ours or another one: polling more often is harmless
            if not job.done:
                if not job.cancel_requested:
                    context.window_manager.progress_update(int(1000 * job.fraction))
                    self._status(context, progress_text(job))
                return {'PASS_THROUGH'}
            self._stop(context)
            return self._finish(context, job, interactive=True)
        return {'PASS_THROUGH'}

    def cancel(self, context):
        # Blender ends the operator (new file, quit): stop the worker, write nothing.
        job = getattr(self, "_job", None)
        if job is not None:
            job.cancel()
            if job.thread is not None:
                job.thread.join()
        self._stop(context)


classes = (OMIS_OT_bake,)
