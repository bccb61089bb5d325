#!/usr/bin/env python3
# The parameter tutorial's calls: global, relative and private reads, defaults, set, search,
# has, delete and list; logs one line "params: <json>" with what it saw.
import json

import rospy

if __name__ == '__main__':
    rospy.init_node('params_node')
    seen = {}
    seen['global'] = rospy.get_param('/global_name')
    seen['relative'] = rospy.get_param('relative_name')
    seen['private'] = rospy.get_param('~private_name')
    seen['default'] = rospy.get_param('default_param', 'default_value')
    seen['gains'] = rospy.get_param('gains')
    rospy.set_param('~set_here', {'p': 1.5, 'list': [1, 2]})
    seen['set_here'] = rospy.get_param('~set_here/list')
    seen['has_private'] = rospy.has_param('~private_name')
    seen['has_missing'] = rospy.has_param('missing_param')
    seen['search'] = rospy.search_param('global_name')
    rospy.delete_param('~set_here')
    seen['deleted'] = not rospy.has_param('~set_here')
    try:
        rospy.get_param('missing_param')
        seen['missing_raises'] = False
    except KeyError:
        seen['missing_raises'] = True
    seen['listed'] = '/global_name' in rospy.get_param_names()
    seen['name'] = rospy.get_name()
    seen['namespace'] = rospy.get_namespace()
    seen['resolved'] = rospy.resolve_name('~private_name')
    rospy.loginfo("params: %s", json.dumps(seen, sort_keys=True))
    rospy.spin()
