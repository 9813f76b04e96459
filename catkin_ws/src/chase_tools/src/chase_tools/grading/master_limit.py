"""The session's ROS master, bounded in what it takes to hold.

Every node of the submission can call the master's XML-RPC API: a `setParam`
of 64 MiB values, again and again, grows it until the kernel kills it at its
memory limit, and the run ends there. roscore runs its master as
`rosmaster`, found on PATH: the grader puts a `rosmaster` first on roscore's
PATH (core.Core) that runs Debian's under this module,

    python -m chase_tools.grading.master_limit RECORD /usr/bin/rosmaster ARGS...

which refuses, before it is read, an XML-RPC request larger than
REQUEST_LIMIT (HTTP 413), and refuses a parameter that would take the
parameters held past PARAMETERS_LIMIT (the API's error code -1, as for any
bad call). Each refusal is kept in RECORD (JSON) for the grader's report.
"""
import json
import os
import runpy
import sys
import threading
import xmlrpc.client

# Any one call: a URDF, the largest parameter a course robot has, is tens of KiB.
REQUEST_LIMIT = 16 << 20
# Every parameter held, by the size of its value as XML-RPC.
PARAMETERS_LIMIT = 64 << 20
# Bytes of the record the grader reads.
RECORD_LIMIT = 64 << 10
SHOWN = 5


class MasterLimit:
    """The refusals of this master, and the size of each parameter it holds."""

    def __init__(self, record=None, request_limit=REQUEST_LIMIT, parameters_limit=PARAMETERS_LIMIT):
        self.record = record
        self.request_limit = request_limit
        self.parameters_limit = parameters_limit
        self.sizes = {}                 # resolved parameter name -> bytes
        self.refused = {}               # ('call' or 'parameter', who) -> (count, the last)
        self.lock = threading.Lock()

    def held(self):
        return sum(self.sizes.values())

    def admit(self, key, size):
        """Whether a value of size may be set at key (it replaces key and whatever is under it)."""
        with self.lock:
            replaced = sum(held for name, held in self.sizes.items() if self.under(name, key))
            return self.held() - replaced + size <= self.parameters_limit

    def took(self, key, size):
        with self.lock:
            self.forget_locked(key)
            self.sizes[key] = size

    def forget(self, key):
        with self.lock:
            self.forget_locked(key)

    def forget_locked(self, key):
        for name in [name for name in self.sizes if self.under(name, key)]:
            del self.sizes[name]

    @staticmethod
    def under(name, key):
        return name == key or name.startswith(key.rstrip('/') + '/')

    def refuse(self, kind, who, example):
        """kind: 'call' or 'parameter'; example: what the last of them was."""
        with self.lock:
            count, _last = self.refused.get((kind, who), (0, None))
            self.refused[(kind, who)] = (count + 1, example)
            if self.record is not None:
                self.write_record()

    def write_record(self):
        shown = sorted(self.refused.items())[:SHOWN]
        text = json.dumps({'request_limit': self.request_limit,
                           'parameters_limit': self.parameters_limit,
                           'refused': [[kind, who, count, example]
                                       for (kind, who), (count, example) in shown]})
        temporary = self.record + '.new'
        with open(temporary, 'w') as stream:
            stream.write(text)
        os.replace(temporary, self.record)

    def install(self):
        """Bound the XML-RPC server's requests and the master's setParam and deleteParam; the
        function that puts them back."""
        from rosgraph.xmlrpc import SilenceableXMLRPCRequestHandler
        from rosmaster import master_api
        limit = self
        unbounded_post = SilenceableXMLRPCRequestHandler.do_POST

        def do_POST(handler):  # noqa: N802 - http.server's name for the handler of a POST
            try:
                length = int(handler.headers.get('content-length', 0))
            except ValueError:
                length = 0
            if length > limit.request_limit:
                # By host: a client retries a refused call from another port.
                limit.refuse('call', str(handler.client_address[0]), '%d bytes' % length)
                handler.send_response(413)
                handler.send_header('Content-length', '0')
                handler.end_headers()
                handler.close_connection = True
                return None
            return unbounded_post(handler)
        SilenceableXMLRPCRequestHandler.do_POST = do_POST

        unbounded_set = master_api.ROSMasterHandler.setParam
        unbounded_delete = master_api.ROSMasterHandler.deleteParam

        def setParam(handler, caller_id, key, value):  # noqa: N802 - the master's XML-RPC name
            try:
                resolved = master_api.resolve_name(key, caller_id)
                size = len(xmlrpc.client.dumps((value,), allow_none=True))
            except Exception:  # noqa: BLE001 - the API's own checks answer a bad call
                return unbounded_set(handler, caller_id, key, value)
            if not limit.admit(resolved, size):
                limit.refuse('parameter', str(caller_id), '%s, %d bytes' % (resolved, size))
                return (-1, 'parameter %s refused: the parameters would hold more than %d bytes'
                        % (resolved, limit.parameters_limit), 0)
            answer = unbounded_set(handler, caller_id, key, value)
            if answer and answer[0] == 1:
                limit.took(resolved, size)
            return answer

        def deleteParam(handler, caller_id, key):  # noqa: N802 - the master's XML-RPC name
            answer = unbounded_delete(handler, caller_id, key)
            if answer and answer[0] == 1:
                try:
                    limit.forget(master_api.resolve_name(key, caller_id))
                except Exception:  # noqa: BLE001 - nothing was held under a bad name
                    pass
            return answer
        master_api.ROSMasterHandler.setParam = setParam
        master_api.ROSMasterHandler.deleteParam = deleteParam

        def uninstall():
            SilenceableXMLRPCRequestHandler.do_POST = unbounded_post
            master_api.ROSMasterHandler.setParam = unbounded_set
            master_api.ROSMasterHandler.deleteParam = unbounded_delete
        return uninstall


def master_notes(record_text):
    """The report's notes on what the master refused, from its RECORD (JSON)."""
    try:
        record = json.loads(record_text)
        notes = []
        for kind, who, count, example in record['refused'][:SHOWN]:
            bound = ('it takes no call larger than %d MiB' % (int(record['request_limit']) >> 20)
                     if kind == 'call' else 'it holds at most %d MiB of parameters'
                     % (int(record['parameters_limit']) >> 20))
            notes.append('the ROS master refused %d %s%s from %s (the last: %s): %s'
                         % (int(count), kind, '' if count == 1 else 's', who, example, bound))
        return notes
    except (ValueError, TypeError, KeyError):
        return ['the ROS master kept a record of refused calls that could not be read']


def run_guarded(argv):
    """RECORD PROGRAM ARGS...: run the master PROGRAM as its own __main__, bounded."""
    record, program = argv[0], argv[1]
    # Before the program's modules are imported: rosmaster_main takes sys.argv as a default.
    sys.argv = [program] + argv[2:]
    MasterLimit(record=record).install()
    runpy.run_path(program, run_name='__main__')


if __name__ == '__main__':
    run_guarded(sys.argv[1:])
