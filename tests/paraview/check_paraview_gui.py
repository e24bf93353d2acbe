"""Refinement in ParaView's GUI, run as `paraview --script=check_paraview_gui.py` in a virtual X
server with the environment variables EXABRICKS_PV_PLUGIN (the plugin) and EXABRICKS_DATA (the
folder of shared samples; else EXABRICKS_DATA_DEFAULT):

plt_small shown as "ExaBricks" with Samples Per Pixel 32 in the GUI's render view. One still
render from the script; the passes after it come from the renders the representation asks of the
view's interactor (Qt's event loop), each adding a few passes, until the image holds 32 passes;
then no further render comes. Exits with 0 when that happened within the time limit, 1
otherwise (and "skipped: ..." with 0 where the shared sample is absent). The GUI sends Python's
output to its own window: the verdict is written to the process's stdout directly."""
import os
import time

import paraview.simple
from paraview.simple import AMReXBoxLibGridReader, ColorBy, GetActiveViewOrCreate, LoadPlugin, Render, Show

SPP = 32
LIMIT = 120.0  # seconds


def say(text):
    os.write(1, (text + "\n").encode())


data_dir = os.environ.get("EXABRICKS_DATA", os.environ.get("EXABRICKS_DATA_DEFAULT", ""))
plotfile = os.path.abspath(os.path.join(data_dir, "amrex", "advection_3d", "plt_small"))
if not os.path.isdir(plotfile):
    say("skipped: shared sample %s is absent (set EXABRICKS_DATA to the folder of shared samples)" % plotfile)
    os._exit(0)
try:
    LoadPlugin(os.environ["EXABRICKS_PV_PLUGIN"], ns=globals())
    reader = AMReXBoxLibGridReader(FileNames=[plotfile])
    reader.CellArrayStatus = ["phi"]
    reader.Level = 10
    view = GetActiveViewOrCreate("RenderView")
    view.OrientationAxesVisibility = 0
    display = Show(reader, view)
    display.Representation = "ExaBricks"
    ColorBy(display, ("CELLS", "phi"))
    display.SamplesPerPixel = SPP
    interactor = view.GetRenderWindow().GetInteractor()
    say("interactor: %s, view %dx%d" % ((interactor.GetClassName(),) + tuple(view.ViewSize)))
except Exception as error:  # the GUI would stay open: end here
    say("FAILED: %s" % error)
    os._exit(1)
history = []  # passes after every render of the view
start = time.time()


def passes():
    display.SMProxy.UpdatePropertyInformation()
    return display.SMProxy.GetProperty("RefinementPasses").GetElement(0)


def verdict():
    say("passes after each render: %s" % history)
    # The view may change while the GUI settles (the first render resets the camera): the
    # passes start over there, and a render that starts over may end with as many passes as the
    # one before it. From the last start they rise to SPP, and no render follows.
    restart = max([i + 1 for i in range(len(history) - 1) if history[i] < SPP and history[i + 1] <= history[i]] + [0])
    tail = history[restart:]
    ok = (len(tail) > 2 and tail[0] < SPP and all(b > a for a, b in zip(tail, tail[1:])) and tail[-1] == SPP)
    say("%d renders, %d of them asked for by the representation, %.1f s"
        % (len(history), len(history) - 1, time.time() - start))
    say("passed" if ok else "FAILED: the passes did not rise to %d over several renders and stop there" % SPP)
    os._exit(0 if ok else 1)


def on_render(caller, event):
    history.append(passes())
    if time.time() - start > LIMIT:
        verdict()


def on_timer(caller, event):
    # A render the representation did not ask for would show here as a render after the image
    # held every pass; the quiet second after the last pass ends the check.
    if history and history[-1] == SPP and time.time() - last_change[0] > 1.0:
        verdict()
    if history and (len(history) != last_change[1]):
        last_change[0], last_change[1] = time.time(), len(history)
    if time.time() - start > LIMIT:
        verdict()


last_change = [time.time(), 0]
view.SMProxy.AddObserver("EndEvent", on_render)
interactor.AddObserver("TimerEvent", on_timer)
interactor.CreateRepeatingTimer(100)
Render(view)
