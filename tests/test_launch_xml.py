"""The XML front end: safe parsing, locations, one <launch> root."""
import pytest

from orchestra.errors import OrchestraError
from orchestra.launch.xml import MAX_DEPTH, parse_bytes, parse_file, parse_string


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


def test_external_entity_declaration_is_refused_at_its_line(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("TOPSECRET")
    doc = (f'<?xml version="1.0"?>\n<!DOCTYPE launch [\n<!ENTITY xxe SYSTEM "file://{secret}">]>\n'
           '<launch><param name="p" value="x"/><rosparam>a: &xxe;</rosparam></launch>')
    with pytest.raises(OrchestraError, match="entity declarations") as info:
        parse_string(doc, "xxe.launch")
    assert str(info.value).startswith("xxe.launch:3:1: ")
    assert "TOPSECRET" not in str(info.value)


def test_billion_laughs_is_refused_before_any_expansion():
    doc = ('<?xml version="1.0"?><!DOCTYPE launch [<!ENTITY a "aaaaaaaaaa">'
           '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;"><!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;">]>'
           '<launch><rosparam>x: &c;</rosparam></launch>')
    with pytest.raises(OrchestraError, match="entity declarations"):
        parse_string(doc, "lol.launch")


def test_multi_line_start_tag_records_the_line_where_it_begins():
    # the line an element records (the plan's) is the line of its '<', as exact positions are
    root = parse_string('<launch>\n<node name="n"\n      if="$(eval 2 > 1)"\n      pkg="p" type="t"\n'
                        '/>\n</launch>\n', "m.launch")
    node = root.children[0]
    assert node.location.line == 2
    assert str(node.where()) == "m.launch:2:1"
    assert str(node.where("pkg")) == "m.launch:4:7"


def test_namespaced_names_are_kept_as_written_and_declarations_dropped():
    root = parse_string('<launch xmlns="urn:a" xmlns:x="urn:x"><x:node x:a="1" b="2"/></launch>')
    assert root.attributes == {}
    assert (root.children[0].tag, root.children[0].attributes) == ("x:node", {"x:a": "1", "b": "2"})


def test_launch_element_inside_another_root_is_found_with_exact_positions():
    root = parse_string("<robot>\n  <x/>\n  <launch>\n    <node a='1'/></launch></robot>", "r.xml")
    assert root.tag == "launch"
    assert str(root.children[0].where("a")) == "r.xml:4:11"


def test_text_of_an_element_joins_text_cdata_and_character_references():
    root = parse_string("<launch><rosparam>a: &amp;x&#10;<![CDATA[b: <y>]]></rosparam></launch>")
    assert root.children[0].text == "a: &x\nb: <y>"


def test_elements_nested_deeper_than_the_bound_are_refused_at_their_line():
    def doc(depth):
        return "<launch>\n" + "<group>" * (depth - 1) + "</group>" * (depth - 1) + "</launch>"
    assert parse_string(doc(MAX_DEPTH), "d").tag == "launch"
    with pytest.raises(OrchestraError, match=f"nested more than {MAX_DEPTH} deep") as info:
        parse_string(doc(MAX_DEPTH + 1), "d")
    assert str(info.value).startswith("d:2:")


@pytest.mark.parametrize("encoding", ["bogus", "utf-32", "shift_jis"])
def test_an_encoding_expat_cannot_read_is_a_located_error(encoding):
    with pytest.raises(OrchestraError, match="declared encoding cannot be read") as info:
        parse_bytes(f'<?xml version="1.0" encoding="{encoding}"?>\n<launch/>\n'.encode(), "e.launch")
    assert str(info.value).startswith("e.launch:1: ")


def test_an_entity_declared_nowhere_read_is_refused_not_dropped():
    # with an external DTD named (never read), expat would skip the reference in the text
    # silently: inline YAML would lose a piece. (In an attribute value expat drops it
    # without telling, as libxml2 did; an entity without a DTD is an error everywhere.)
    doc = ('<!DOCTYPE launch SYSTEM "launch.dtd">\n<launch>\n'
           '  <rosparam>a: x&foo;y</rosparam>\n</launch>\n')
    with pytest.raises(OrchestraError, match="undefined entity &foo;") as info:
        parse_string(doc, "u.launch")
    assert str(info.value).startswith("u.launch:3:")
    with pytest.raises(OrchestraError, match="undefined entity"):
        parse_string('<launch><param name="a" value="x&foo;y"/></launch>', "u.launch")


def test_missing_file_is_a_user_error(tmp_path):
    with pytest.raises(OrchestraError, match="cannot read"):
        parse_file(str(tmp_path / "nope.launch"))
