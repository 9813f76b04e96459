"""The TurtleSim window: a Tk window that shows the latest canvas picture.

Tk must run in the main thread; the simulation runs elsewhere and hands
pictures over through a callable that returns the newest one (or None when
nothing changed since the last call). The window closes when is_running()
turns false; closing it by hand calls on_close().
"""
import os

REFRESH_MS = 33


class WindowUnavailable(RuntimeError):
    """There is no display to open a window on; the message says why."""


def encode_ppm(frame):
    """A binary PPM of an RGB uint8 image (rows, columns, 3): Tk reads it without PIL."""
    rows, columns = frame.shape[:2]
    return b'P6 %d %d 255\n' % (columns, rows) + frame.tobytes()


class CanvasWindow:
    def __init__(self, title, next_picture, is_running, on_close):
        """Raises WindowUnavailable when there is no display."""
        if not os.environ.get('DISPLAY'):
            raise WindowUnavailable('DISPLAY is not set')
        # Imported here so that a machine without python3-tk still runs headless.
        try:
            import tkinter
        except ImportError as error:
            raise WindowUnavailable('python3-tk is not installed') from error
        try:
            self.root = tkinter.Tk()
        except tkinter.TclError as error:
            raise WindowUnavailable(str(error)) from error
        self.root.title(title)
        self.root.resizable(False, False)
        self.photo = tkinter.PhotoImage(master=self.root)
        tkinter.Label(self.root, image=self.photo, borderwidth=0).pack()
        self.next_picture = next_picture
        self.is_running = is_running
        self.on_close = on_close
        self.root.protocol('WM_DELETE_WINDOW', self.close)
        self.root.after(0, self._refresh)

    def show(self, frame):
        self.photo.configure(data=encode_ppm(frame), format='PPM')

    def run(self):
        self.root.mainloop()
        self.root.destroy()

    def close(self):
        self.on_close()
        self.root.quit()

    def _refresh(self):
        if not self.is_running():
            self.root.quit()
            return
        frame = self.next_picture()
        if frame is not None:
            self.show(frame)
        self.root.after(REFRESH_MS, self._refresh)
