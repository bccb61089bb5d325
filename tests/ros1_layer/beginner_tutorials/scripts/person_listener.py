#!/usr/bin/env python3
# Receives beginner_tutorials/Person on people and logs each one.
import rospy
from beginner_tutorials.msg import Person


def on_person(person):
    rospy.loginfo("got person %s aged %d who likes %s (%s)", person.name, person.age,
                  ",".join(person.hobbies[:2]), person._type)


if __name__ == '__main__':
    rospy.init_node('person_listener')
    rospy.Subscriber('people', Person, on_person)
    rospy.spin()
