"""Operators for baking on other machines: Export Bake Job, Import Bake Job Results
(bake_job_files does the work; `python3 -m omis bake JOB.json` bakes in between)."""

import bpy
from bpy.props import StringProperty

from . import bake_job_files
from .errors import BakeError


class OMIS_OT_export_bake_job(bpy.types.Operator):
    """Write the selected objects' bake as a job for another machine or a farm: a scene
    snapshot and a job file (bake it with `python3 -m omis bake JOB.json`)"""
    bl_idname = "omis.export_bake_job"
    bl_label = "Export Bake Job"
    bl_options = {'REGISTER'}

    filepath: StringProperty(name="Job File", subtype='FILE_PATH', default="//omis_job/job.json")

    def execute(self, context):
        path = bpy.path.abspath(self.filepath)
        try:
            data = bake_job_files.export_bake_job(context, path)
        except (BakeError, ValueError, OSError) as exc:
            self.report({'ERROR'}, str(exc))
            return {'CANCELLED'}
        self.report({'INFO'}, f'Exported {len(data["units"])} bake units to {path}: '
                              f'python3 -m omis bake "{path}"')
        return {'FINISHED'}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {'RUNNING_MODAL'}


class OMIS_OT_import_bake_job_results(bpy.types.Operator):
    """Write a baked job's results into the images and color attributes it was exported
    from (nothing is written when a result is missing or the scene changed)"""
    bl_idname = "omis.import_bake_job_results"
    bl_label = "Import Bake Job Results"
    bl_options = {'REGISTER', 'UNDO'}

    filepath: StringProperty(name="Job File", subtype='FILE_PATH', default="//omis_job/job.json")

    def execute(self, context):
        try:
            stats = bake_job_files.import_bake_job_results(context, bpy.path.abspath(self.filepath))
        except (BakeError, ValueError, OSError) as exc:
            self.report({'ERROR'}, str(exc))
            return {'CANCELLED'}
        targets = stats["images"] + stats["attributes"]
        self.report({'INFO'}, "Imported the bake job's results into " + ", ".join(targets))
        return {'FINISHED'}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {'RUNNING_MODAL'}


classes = (OMIS_OT_export_bake_job, OMIS_OT_import_bake_job_results)
