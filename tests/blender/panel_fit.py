"""Does the omis panel's text fit a Properties editor of a given width?

Blender does not tell Python where it placed a label or whether it cut it short,
and there is no OCR here; so the panel is drawn into a recording layout, and a
model of Blender's layout (the widths rows, splits, boxes and split properties
give their items; omis_bake.ui's margins) hands every text its room, which its
width in Blender's UI font (blf) must not exceed. The screenshots of
test_panel_screenshot.py show whether the model matches what Blender draws.
Checked against Blender 3.4 at the default width (303-pixel region, UI scale 1.04):
texts the model gave 106 of 108 and 100 of 108 pixels were drawn whole, texts it
gave 115 of 108, 121 of 114 and 265 of 253 were cut ("Samples per tex…").

    too_long = overflows(draw, region_width)   # [(text, width, room)], empty when all fit
"""

import bpy

from omis_bake import ui


class _Item:
    """One call on a layout: a sub-layout (row, column, box, split) or a leaf."""

    def __init__(self, kind, split_props, **info):
        self.kind = kind
        self.children = []
        self.info = info
        self.split_props = split_props

    # -- the layout API the panel uses --

    def __setattr__(self, name, value):
        if name == "use_property_split":
            object.__setattr__(self, "split_props", bool(value))
        else:
            object.__setattr__(self, name, value)

    def _child(self, kind, **info):
        item = _Item(kind, self.split_props, **info)
        self.children.append(item)
        return item

    def row(self, heading="", **_):
        return self._child("row", heading=heading)

    def column(self, heading="", **_):
        return self._child("column", heading=heading)

    def box(self):
        return self._child("box")

    def split(self, factor=0.0, **_):
        return self._child("split", factor=factor)

    def label(self, text="", icon='NONE', **_):
        self._child("label", text=text, icon=icon)

    def separator(self, **_):
        pass

    def operator(self, idname, text=None, icon='NONE', **_):
        self._child("label", text=text or idname, icon=icon)
        return _Item("operator_properties", False)

    def prop(self, data, name, text=None, icon='NONE', expand=False, **_):
        rna = data.bl_rna.properties[name]
        label = rna.name if text is None else text
        self._child("prop", data=data, rna=rna, label=label, icon=icon, expand=expand)


def _texts(item, room, out):
    """(text, room) pairs of every text under `item` given `room` pixels."""
    scale = ui.ui_scale()
    icon = ui.ICON_WIDTH * scale

    def need(text, has_icon):
        return ui.text_width(text) + ui.TEXT_MARGIN * scale + (icon if has_icon else 0)

    if item.kind == "label":
        if item.info["text"]:
            out.append((item.info["text"], need(item.info["text"], item.info["icon"] != 'NONE'),
                        room))
        return
    if item.kind == "prop":
        _prop_texts(item, room, out, need)
        return
    if item.kind == "box":
        room -= 2 * ui.BOX_PADDING * scale
    children = item.children
    if item.kind == "split" and children:
        f = item.info["factor"] or 0.5
        _texts(children[0], f * room, out)
        for child in children[1:]:
            _texts(child, (1 - f) * room / max(len(children) - 1, 1), out)
        return
    if item.kind == "row":
        heading = item.info.get("heading")
        if heading and item.split_props:
            out.append((heading, need(heading, False), ui.PROPERTY_SPLIT * room))
            room *= 1 - ui.PROPERTY_SPLIT
        share = room / max(len(children), 1)
        for child in children:
            _texts(child, share, out)
        return
    for child in children:   # column, box, the panel itself
        _texts(child, room, out)


def _prop_texts(item, room, out, need):
    rna, label, data = item.info["rna"], item.info["label"], item.info["data"]
    value = None
    if rna.type == 'ENUM' and not rna.is_enum_flag and not item.info["expand"]:
        current = getattr(data, rna.identifier)
        value = next(e.name for e in rna.enum_items if e.identifier == current)
    if rna.type == 'ENUM' and (rna.is_enum_flag or item.info["expand"]):
        # Expanded items, one per line in a column: each item's own button.
        for e in rna.enum_items:
            out.append((e.name, need(e.name, False), room))
        return
    if item.split_props and rna.type != 'BOOLEAN':
        if label:
            out.append((label, need(label, False), ui.PROPERTY_SPLIT * room))
        if value:   # a drop-down: the current item beside its arrow
            out.append((value, need(value, True), (1 - ui.PROPERTY_SPLIT) * room))
        return
    if item.split_props:   # a checkbox and its text in the value column
        room *= 1 - ui.PROPERTY_SPLIT
    if label:
        has_icon = rna.type == 'BOOLEAN' or item.info["icon"] != 'NONE'
        out.append((label, need(label, has_icon), room))


class _Context:
    """bpy.context with a region of a chosen width (the panel wraps text to it)."""

    def __init__(self, region_width):
        self.region = type("Region", (), {"width": region_width})()

    def __getattr__(self, name):
        return getattr(bpy.context, name)


def texts(draw, region_width):
    """(text, needed pixels, room in pixels) for everything `draw(layout, context)` shows
    in a region `region_width` pixels wide."""
    root = _Item("column", False)
    draw(root, _Context(region_width))
    out = []
    _texts(root, region_width - 2 * ui.PANEL_MARGIN * ui.ui_scale(), out)
    return out


def overflows(draw, region_width):
    """The texts that do not fit: [(text, needed, room)]."""
    return [(t, need, room) for t, need, room in texts(draw, region_width) if need > room]


def header_fits(label, progress, region_width):
    """(needed, room): the panel's header — collapse arrow, name, the progress at the
    right end, the drag handle's room — in a region `region_width` wide."""
    scale = ui.ui_scale()
    icon = ui.ICON_WIDTH * scale
    needed = (icon + ui.text_width(label) + ui.TEXT_MARGIN * scale
              + ui.text_width(progress) + ui.TEXT_MARGIN * scale + icon)
    return needed, region_width - 2 * ui.PANEL_MARGIN * scale
