# A drag source for one file, offered as a file manager offers it (text/uri-list), for
# input-check.sh to drag onto the viewer: python3 drag_source.py FILE
import sys, gi
gi.require_version('Gtk', '3.0')
from gi.repository import Gtk, Gdk
path = sys.argv[1]
w = Gtk.Window(title="drag source")
w.move(1300, 800)
b = Gtk.Button(label="drag me")
b.drag_source_set(Gdk.ModifierType.BUTTON1_MASK, [], Gdk.DragAction.COPY)
b.drag_source_add_uri_targets()
def get(widget, ctx, data, info, time):
    data.set_uris(["file://" + path])
b.connect("drag-data-get", get)
w.add(b)
w.set_default_size(90, 60)
w.connect("destroy", Gtk.main_quit)
w.show_all()
Gtk.main()
