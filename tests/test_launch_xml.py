"""The XML front end: safe parsing, locations, one <launch> root."""
import pytest

from orchestra.errors import OrchestraError
from orchestra.launch.xml import parse_file, parse_string


def test_entities_carry_tag_attributes_children_and_lines():
    root = parse_string('<launch>\n  <group ns="a">\n    <node name="n" pkg="p" type="t"/>\n'
                        '  </group>\n</launch>\n', "demo.launch")
    group = root.children[0]
    node = group.children[0]
    assert (root.tag, group.tag, node.tag) == ("launch", "group", "node")
    assert node.attributes == {"name": "n", "pkg": "p", "type": "t"}
    assert (node.location.file, node.location.line) == ("demo.launch", 3)


def test_rosparam_text_skips_comments_but_keeps_surrounding_text():
    root = parse_string("<launch><rosparam>a: 1\n<!-- c -->b: 2\n</rosparam></launch>")
    assert root.children[0].text == "a: 1\nb: 2\n"


def test_malformed_xml_is_a_located_error(tmp_path):
    path = tmp_path / "bad.launch"
    path.write_text("<launch>\n  <node name='x'\n</launch>\n")
    with pytest.raises(OrchestraError) as info:
        parse_file(str(path))
    assert str(info.value).startswith(f"{path}:")


def test_document_without_launch_element_is_rejected():
    with pytest.raises(OrchestraError, match="<launch>"):
        parse_string("<robot/>", "r.xml")


def test_external_entities_are_not_expanded(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("TOPSECRET")
    doc = (f'<?xml version="1.0"?>\n<!DOCTYPE launch [<!ENTITY xxe SYSTEM "file://{secret}">]>\n'
           '<launch><param name="p" value="x"/><rosparam>a: &xxe;</rosparam></launch>')
    root = parse_string(doc, "xxe.launch")
    assert "TOPSECRET" not in (root.children[1].text or "")
    assert all("TOPSECRET" not in v for c in root.children for v in c.attributes.values())


def test_billion_laughs_does_not_expand():
    doc = ('<?xml version="1.0"?><!DOCTYPE launch [<!ENTITY a "aaaaaaaaaa">'
           '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;"><!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;">]>'
           '<launch><rosparam>x: &c;</rosparam></launch>')
    root = parse_string(doc, "lol.launch")
    assert len(root.children[0].text or "") < 100


def test_missing_file_is_a_user_error(tmp_path):
    with pytest.raises(OrchestraError, match="cannot read"):
        parse_file(str(tmp_path / "nope.launch"))
