"""Names that come with requests, as log lines show them.

A request can carry a name of any length, and rosout writes each log line to
several files: a line shows a name's first MAX_LOGGED_CHARS characters and
says how long it was. No ROS here.
"""
MAX_LOGGED_CHARS = 200


def logged_name(name):
    """name as a log line shows it: whole if short, else cut with its length said."""
    text = name if isinstance(name, str) else str(name)
    if len(text) <= MAX_LOGGED_CHARS:
        return text
    return '%s... (%d characters)' % (text[:MAX_LOGGED_CHARS], len(text))
