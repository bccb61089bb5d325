#!/usr/bin/env python3
# Publishes the package's own message type, beginner_tutorials/Person, on people.
import rospy
from beginner_tutorials.msg import Person

if __name__ == '__main__':
    rospy.init_node('person_publisher')
    pub = rospy.Publisher('people', Person, queue_size=10)
    name = rospy.get_param('~name', 'Ada')
    rate = rospy.Rate(5)
    count = 0
    while not rospy.is_shutdown():
        msg = Person()
        msg.name = name
        msg.age = 36
        msg.hobbies = ['maths', 'engines', str(count)]
        pub.publish(msg)
        count += 1
        try:
            rate.sleep()
        except rospy.ROSInterruptException:
            break
