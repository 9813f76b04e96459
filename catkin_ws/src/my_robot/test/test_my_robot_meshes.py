"""meshes/hokuyo.dae is a well-formed COLLADA 1.4.1 document whose mesh fills
the hokuyo link's collision box."""
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

PACKAGE_DIR = pathlib.Path(__file__).resolve().parent.parent
NS = '{http://www.collada.org/2005/11/COLLADASchema}'
MESH = PACKAGE_DIR / 'meshes' / 'hokuyo.dae'


@pytest.fixture(scope='module')
def dae():
    return ET.parse(MESH).getroot()


def sources(mesh):
    """source id -> (n, 3) array, checked against its float_array and accessor counts."""
    out = {}
    for source in mesh.findall(NS + 'source'):
        array = source.find(NS + 'float_array')
        values = np.array(array.text.split(), dtype=float)
        assert len(values) == int(array.get('count'))
        accessor = source.find(NS + 'technique_common/' + NS + 'accessor')
        assert accessor.get('source') == '#' + array.get('id')
        stride = int(accessor.get('stride'))
        assert stride == 3 and int(accessor.get('count')) * stride == len(values)
        out[source.get('id')] = values.reshape(-1, 3)
    return out


def triangles(mesh):
    """(positions of each triangle corner (t, 3, 3), listed normal of each corner (t, 3, 3))."""
    table = sources(mesh)
    vertices = mesh.find(NS + 'vertices')
    position_source = vertices.find(NS + 'input[@semantic="POSITION"]').get('source').lstrip('#')
    corners, normals = [], []
    for tris in mesh.findall(NS + 'triangles'):
        inputs = {i.get('semantic'): (i.get('source').lstrip('#'), int(i.get('offset')))
                  for i in tris.findall(NS + 'input')}
        assert inputs['VERTEX'][0] == vertices.get('id')
        indices = np.array(tris.find(NS + 'p').text.split(), dtype=int).reshape(-1, len(inputs))
        assert len(indices) == 3 * int(tris.get('count'))
        corners.append(table[position_source][indices[:, inputs['VERTEX'][1]]])
        normals.append(table[inputs['NORMAL'][0]][indices[:, inputs['NORMAL'][1]]])
    return np.concatenate(corners).reshape(-1, 3, 3), np.concatenate(normals).reshape(-1, 3, 3)


def test_document_is_collada_1_4_1_with_the_required_sections(dae):
    assert dae.tag == NS + 'COLLADA'
    assert dae.get('version') == '1.4.1'
    sections = [child.tag[len(NS):] for child in dae]
    assert sections[0] == 'asset' and sections[-1] == 'scene'
    assert {'library_geometries', 'library_visual_scenes', 'library_materials', 'library_effects'} <= set(sections)
    unit = dae.find(NS + 'asset/' + NS + 'unit')
    assert float(unit.get('meter')) == 1.0
    assert dae.findtext(NS + 'asset/' + NS + 'up_axis') == 'Z_UP'


def test_every_reference_names_an_element_in_the_document(dae):
    ids = {e.get('id') for e in dae.iter() if e.get('id')}
    refs = [e.get(attr) for e in dae.iter() for attr in ('url', 'source', 'target') if e.get(attr)]
    assert refs
    assert all(ref.startswith('#') and ref[1:] in ids for ref in refs)
    symbols = {t.get('material') for t in dae.iter(NS + 'triangles')}
    bound = {m.get('symbol') for m in dae.iter(NS + 'instance_material')}
    assert symbols <= bound


def test_faces_wind_outwards_as_their_normals_say(dae):
    for mesh in dae.iter(NS + 'mesh'):
        corners, normals = triangles(mesh)
        assert len(corners) >= 12
        geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        assert np.all(np.einsum('ij,ij->i', geometric, normals[:, 0]) > 0)


def test_mesh_fills_the_hokuyo_collision_box(dae, urdf_root):
    box = urdf_root('diff').find("link[@name='hokuyo']/collision/geometry/box")
    half = np.array(box.get('size').split(), dtype=float) / 2
    points = np.concatenate([triangles(mesh)[0].reshape(-1, 3) for mesh in dae.iter(NS + 'mesh')])
    assert points.min(axis=0) == pytest.approx(-half, abs=1e-9)
    assert points.max(axis=0) == pytest.approx(half, abs=1e-9)
