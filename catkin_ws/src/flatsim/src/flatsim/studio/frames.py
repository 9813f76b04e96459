"""How the hub's messages go to a page: JSON text, and camera images as binary frames. No ROS here."""
import json
import struct

from flatsim.studio.protocol import CommandError

# Camera images go to the page at most this wide (a panel shows them smaller still).
CAMERA_MAX_WIDTH = 480
JPEG_QUALITY = 80


def dumps(message):
    return json.dumps(message, separators=(',', ':'), allow_nan=False)


def camera_frame(sensor, sim_time, pixels):
    """The binary frame for a camera image: header length, JSON header, JPEG (pixels rgb8)."""
    import cv2  # only tabs with the camera panel open pay for it
    height, width = pixels.shape[:2]
    if width > CAMERA_MAX_WIDTH:
        height = max(1, round(height * CAMERA_MAX_WIDTH / width))
        width = CAMERA_MAX_WIDTH
        pixels = cv2.resize(pixels, (width, height), interpolation=cv2.INTER_AREA)
    bgr = cv2.cvtColor(pixels, cv2.COLOR_RGB2BGR) if pixels.ndim == 3 else pixels
    ok, jpeg = cv2.imencode('.jpg', bgr, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    if not ok:
        raise CommandError('the camera image could not be encoded')
    header = dumps({'type': 'camera_image', 'sensor': sensor, 'sim_time': round(sim_time, 4),
                    'width': width, 'height': height}).encode()
    return struct.pack('>I', len(header)) + header + jpeg.tobytes()
